// The AMP discriminator (Peng et al. 2021): D(s_p over the last frames) -> a logit that the
// motion is from the reference data, with the gradient penalty on reference samples.
#ifndef MODSKILL_LEARNER_AMP_DISCRIMINATOR_H_
#define MODSKILL_LEARNER_AMP_DISCRIMINATOR_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "learner/part_controller.h"

namespace modskill::learner {

class AmpDiscriminatorImpl : public torch::nn::Module {
 public:
  AmpDiscriminatorImpl(int64_t amp_obs_size, const std::vector<int64_t>& hidden);

  // amp_obs: [B, amp_obs_size] -> logit: [B] (ReLU MLP, linear output)
  torch::Tensor forward(const torch::Tensor& amp_obs);

  // expert_amp_obs: [B, amp_obs_size] -> [] = mean_b ||d logit_b / d x_b||^2 (AMP, Eq. 8), with
  // create_graph so that it can be minimized. The input is detached first.
  torch::Tensor GradientPenalty(const torch::Tensor& expert_amp_obs);

  Mlp& mlp() { return mlp_; }

 private:
  Mlp mlp_;
};
TORCH_MODULE(AmpDiscriminator);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_AMP_DISCRIMINATOR_H_
