// Variable time-step GAE (Lee et al. 2021, Eq. 9): a step advances the reference by a phase
// Delta-phi chosen by the policy (the time warp), so discounting follows phase, not steps:
//   delta_t = (int_0^dphi gamma^x dx) r_c + r_s + gamma^dphi V(s_{t+1}) - V(s_t)
//   A_t     = delta_t + (gamma lambda)^dphi A_{t+1}
// Phase is measured in the clip's control frames: dphi = 1 is the clip's own pace.
#ifndef MODSKILL_LEARNER_FAMILY_VARIABLE_STEP_GAE_H_
#define MODSKILL_LEARNER_FAMILY_VARIABLE_STEP_GAE_H_

#include <torch/torch.h>

#include "absl/status/statusor.h"

namespace modskill::learner::family {

// A rollout of T steps from N envs; every tensor [T, N] unless said otherwise.
struct VariableStepRollout {
  torch::Tensor continuous_reward;  // r_c: a reward rate per unit phase (tracking, continuous task terms)
  torch::Tensor spike_reward;       // r_s: reward of an event (goal reached); not scaled by dphi
  torch::Tensor phase_step;         // dphi > 0, finite
  torch::Tensor values;             // V(s_t)
  torch::Tensor terminated;         // 1 where the episode failed after step t: V(s_{t+1}) = 0
  // 1 where it timed out after step t: V(s_{t+1}) = timeout_values (the row's next observation
  // already belongs to the next episode, so the caller supplies V of the state it ended in).
  // Both may be left undefined when no episode times out.
  torch::Tensor truncated;
  torch::Tensor timeout_values;
  torch::Tensor last_values;        // [N], V of the observation after step T-1
};

struct Advantages {
  torch::Tensor advantages;  // [T, N], A_t (Eq. 9)
  torch::Tensor returns;     // [T, N], A_t + V(s_t): the critic's target
};

// The weight of the continuous reward over a step of length dphi: Eq. 9's integral divided by
// its value over a unit step,
//   w(dphi) = int_0^dphi gamma^x dx / int_0^1 gamma^x dx = (gamma^dphi - 1) / (gamma - 1).
// Why normalized: r_c is read as "the reward of one clip frame at the clip's pace", the
// scale ordinary GAE and the tracking reward's weights assume, so a step with dphi = 1 weighs it
// by exactly 1 and the constant-step case is ordinary GAE with no rescaled rewards. Unnormalized,
// every continuous reward would shrink by (gamma - 1)/ln(gamma) (0.975 at gamma = 0.95), a
// constant that only shifts the continuous/spike balance the task weights set. w is additive
// over consecutive steps: w(a + b) = w(a) + gamma^a w(b).
double ContinuousRewardWeight(double gamma, double phase_step);

// Eq. 9 backwards over the rollout, computed in float64 and returned in the values' dtype.
// A failure stops the bootstrap (V' = 0) and the trace; a time-out bootstraps from
// timeout_values and stops the trace. gamma in (0, 1), lambda in [0, 1]. INVALID_ARGUMENT,
// naming the field, for a wrong shape, a non-finite entry or dphi <= 0. With dphi = 1 and
// r_s = 0 everywhere this is ComputeGae (learner/gae.h) on r_c + gamma timeout_values
// truncated, with dones = terminated or truncated: the trainer's own time-out treatment.
absl::StatusOr<Advantages> ComputeVariableStepGae(const VariableStepRollout& rollout, double gamma,
                                                  double lambda);

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_VARIABLE_STEP_GAE_H_
