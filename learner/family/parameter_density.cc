#include "learner/family/parameter_density.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {

absl::Status ParameterDensity::Add(absl::Span<const double> params) {
  if (static_cast<int>(params.size()) != dims()) {
    return absl::InvalidArgumentError(absl::StrCat("parameter density: point has ", params.size(), " values, expected ", dims()));
  }
  for (size_t i = 0; i < params.size(); ++i) {
    if (!(params[i] >= 0 && params[i] <= 1)) {
      return absl::InvalidArgumentError(absl::StrCat("parameter density: normalized param ", i, " = ", params[i], " outside [0, 1]"));
    }
  }
  if (absl::Status s = tree_.Insert(size(), params); !s.ok()) return s;
  points_.emplace_back(params.begin(), params.end());
  return absl::OkStatus();
}

double ParameterDensity::Evaluate(absl::Span<const double> params) const {
  const double h = config_.bandwidth;
  double sum = 0;
  for (const Neighbor& n : tree_.WithinRadius(params, 3 * h)) sum += std::exp(-n.distance * n.distance / (2 * h * h));
  return std::min(1.0, sum / config_.saturation);
}

}  // namespace modskill::learner::family
