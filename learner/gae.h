// Generalized Advantage Estimation (Schulman et al. 2016, "High-Dimensional Continuous
// Control Using Generalized Advantage Estimation", Sec. 3, eq. 11-16).
#ifndef MODSKILL_LEARNER_GAE_H_
#define MODSKILL_LEARNER_GAE_H_

#include <torch/torch.h>

namespace modskill::learner {

// Advantages and value targets for a rollout of T steps from N envs.
//   rewards, values, dones: [T, N] float. dones[t] = 1 where the episode ended after step t,
//                           so V(s_{t+1}) is not bootstrapped across it (the next row belongs
//                           to a new episode).
//   last_values:            [N], V of the observation after the last step (row T).
// Writes advantages [T, N] (A_t = delta_t + gamma * lambda * (1 - done_t) * A_{t+1}) and
// returns [T, N] = A + V. No gradient flows through either output.
void ComputeGae(const torch::Tensor& rewards, const torch::Tensor& values,
                const torch::Tensor& dones, const torch::Tensor& last_values, double gamma,
                double lambda, torch::Tensor* advantages, torch::Tensor* returns);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_GAE_H_
