#include "learner/gae.h"

#include <utility>

namespace modskill::learner {

void ComputeGae(const torch::Tensor& rewards, const torch::Tensor& values,
                const torch::Tensor& dones, const torch::Tensor& last_values, double gamma,
                double lambda, torch::Tensor* advantages, torch::Tensor* returns) {
  TORCH_CHECK(rewards.dim() == 2, "ComputeGae: rewards must be [T, N], got ", rewards.sizes());
  TORCH_CHECK(values.sizes() == rewards.sizes() && dones.sizes() == rewards.sizes(),
              "ComputeGae: rewards ", rewards.sizes(), ", values ", values.sizes(), " and dones ",
              dones.sizes(), " must have the same [T, N] shape");
  TORCH_CHECK(last_values.dim() == 1 && last_values.size(0) == rewards.size(1),
              "ComputeGae: last_values must be [N] = [", rewards.size(1), "], got ",
              last_values.sizes());
  torch::NoGradGuard no_grad;
  const torch::Tensor not_done = 1.0 - dones.to(rewards.dtype());
  torch::Tensor adv = torch::empty_like(rewards);
  torch::Tensor next_value = last_values.detach();
  torch::Tensor next_adv = torch::zeros_like(next_value);
  for (int64_t t = rewards.size(0) - 1; t >= 0; --t) {
    // TD residual: delta_t = r_t + gamma * V(s_{t+1}) - V(s_t), no bootstrap past a done.
    const torch::Tensor delta = rewards[t] + gamma * next_value * not_done[t] - values[t];
    // Eq. 16, A_t = sum_l (gamma lambda)^l delta_{t+l}, as a backward recursion.
    next_adv = delta + gamma * lambda * not_done[t] * next_adv;
    adv[t] = next_adv;
    next_value = values[t];
  }
  *returns = adv + values.detach();
  *advantages = std::move(adv);
}

}  // namespace modskill::learner
