// The value function V(s): an ELU MLP from the normalized observation to one value.
#ifndef MODSKILL_LEARNER_CRITIC_H_
#define MODSKILL_LEARNER_CRITIC_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "learner/part_controller.h"

namespace modskill::learner {

class CriticImpl : public torch::nn::Module {
 public:
  CriticImpl(int64_t obs_size, const std::vector<int64_t>& hidden);

  // normalized_obs: [B, obs_size] -> value: [B]
  torch::Tensor forward(const torch::Tensor& normalized_obs);

 private:
  Mlp mlp_;
};
TORCH_MODULE(Critic);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_CRITIC_H_
