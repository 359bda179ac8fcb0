#include "learner/family/elite_bootstrap.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {

absl::StatusOr<torch::Tensor> BootstrapTrajectory(const EliteSet& elites, absl::Span<const double> params,
                                                  const EliteBootstrapConfig& config) {
  if (config.neighbors < 1 || !(config.sigma > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("elite bootstrap: neighbors ", config.neighbors, " must be >= 1 and sigma ", config.sigma, " > 0"));
  }
  if (static_cast<int>(params.size()) != elites.dims()) {
    return absl::InvalidArgumentError(
        absl::StrCat("elite bootstrap: params have ", params.size(), " values, expected ", elites.dims()));
  }
  if (elites.size() == 0) return absl::FailedPreconditionError("elite bootstrap: the elite set is empty");
  torch::NoGradGuard no_grad;
  torch::Tensor blend = torch::zeros({elites.frames(), elites.outputs()});
  double weight_sum = 0;
  for (const Neighbor& n : elites.Nearest(params, config.neighbors)) {
    const Elite& elite = elites.elite(n.id);
    // w_k = F_k exp(-|a_k - a|^2 / sigma_k^2)
    const double w = elite.fitness * std::exp(-n.distance * n.distance / (config.sigma * config.sigma));
    if (!(w > 0)) continue;  // an elite with F <= 0 cannot pull the blend
    blend += w * elite.trajectory;
    weight_sum += w;
  }
  if (!(weight_sum > 0)) {
    return absl::FailedPreconditionError("elite bootstrap: every nearby elite has weight 0 (fitness <= 0 or too far)");
  }
  return blend / weight_sum;
}

}  // namespace modskill::learner::family
