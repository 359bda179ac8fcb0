#include "learner/amp_discriminator.h"

namespace modskill::learner {

AmpDiscriminatorImpl::AmpDiscriminatorImpl(int64_t amp_obs_size, const std::vector<int64_t>& hidden)
    : mlp_(register_module("mlp", Mlp(amp_obs_size, hidden, 1, Activation::kRelu))) {}

torch::Tensor AmpDiscriminatorImpl::forward(const torch::Tensor& amp_obs) { return mlp_->forward(amp_obs).squeeze(-1); }

torch::Tensor AmpDiscriminatorImpl::GradientPenalty(const torch::Tensor& expert_amp_obs) {
  torch::AutoGradMode enable_grad(true);
  const torch::Tensor x = expert_amp_obs.detach().requires_grad_(true);  // [B, D]
  const torch::Tensor logit = forward(x);                                // [B]
  const torch::Tensor grad = torch::autograd::grad({logit.sum()}, {x}, /*grad_outputs=*/{}, /*retain_graph=*/true,
                                                   /*create_graph=*/true)[0];  // [B, D]
  return grad.square().sum(-1).mean();
}

}  // namespace modskill::learner
