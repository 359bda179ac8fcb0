#include "learner/critic.h"

namespace modskill::learner {

CriticImpl::CriticImpl(int64_t obs_size, const std::vector<int64_t>& hidden)
    : mlp_(register_module("mlp", Mlp(obs_size, hidden, 1, Activation::kElu))) {}

torch::Tensor CriticImpl::forward(const torch::Tensor& normalized_obs) {
  return mlp_->forward(normalized_obs).squeeze(-1);
}

}  // namespace modskill::learner
