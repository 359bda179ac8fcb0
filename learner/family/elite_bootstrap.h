// The bootstrap of the parameterization (Lee et al. 2021; DESIGN.md section 4): before the
// network knows a region, the motion for parameters a blends the k = 5 nearest elites'
// trajectories with weights
//   w_k = F_k exp(-|a_k - a|^2 / sigma_k^2),  sigma_k = 0.28 (normalized parameter units),
// so a fitter and a closer elite count more. The blend is linear in (d_t, tau_t): d holds
// exp-map displacements, which blend well while they are small (a displacement of a clip, not a
// new motion), and tau is a log time step.
#ifndef MODSKILL_LEARNER_FAMILY_ELITE_BOOTSTRAP_H_
#define MODSKILL_LEARNER_FAMILY_ELITE_BOOTSTRAP_H_

#include <torch/torch.h>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "learner/family/elite_set.h"

namespace modskill::learner::family {

struct EliteBootstrapConfig {
  int neighbors = 5;     // k
  double sigma = 0.28;   // sigma_k
};

// [L, D]: sum_k w_k trajectory_k / sum_k w_k over the min(k, size) nearest elites.
// FAILED_PRECONDITION for an empty set or when every weight is 0 (no elite with F > 0 near
// enough to count); INVALID_ARGUMENT for parameters of the wrong size or a config with
// neighbors < 1 or sigma <= 0.
absl::StatusOr<torch::Tensor> BootstrapTrajectory(const EliteSet& elites, absl::Span<const double> params,
                                                  const EliteBootstrapConfig& config = {});

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_ELITE_BOOTSTRAP_H_
