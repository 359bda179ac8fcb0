#include "server/core/curriculum/clip_sampler.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

ClipSampler::ClipSampler(int num_clips) : weights_(std::max(num_clips, 1), 1.0), cumulative_(weights_.size()) {
  for (size_t i = 0; i < weights_.size(); ++i) cumulative_[i] = static_cast<double>(i + 1);
}

absl::Status ClipSampler::SetWeights(absl::Span<const double> weights) {
  if (weights.size() != weights_.size()) {
    return absl::InvalidArgumentError(absl::StrCat("weights: ", weights.size(), " values for ", weights_.size(), " clips"));
  }
  double total = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    if (!std::isfinite(weights[i]) || weights[i] < 0) {
      return absl::InvalidArgumentError(absl::StrCat("weights[", i, "]: ", weights[i], " is not a finite value >= 0"));
    }
    total += weights[i];
  }
  if (!(total > 0)) return absl::InvalidArgumentError("weights: sum is zero");
  weights_.assign(weights.begin(), weights.end());
  double running = 0;
  for (size_t i = 0; i < weights_.size(); ++i) cumulative_[i] = running += weights_[i];
  return absl::OkStatus();
}

int ClipSampler::Sample(std::mt19937_64& rng) const {
  const double u = std::uniform_real_distribution<double>(0.0, cumulative_.back())(rng);
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
  return std::min(static_cast<int>(it - cumulative_.begin()), num_clips() - 1);
}

}  // namespace modskill
