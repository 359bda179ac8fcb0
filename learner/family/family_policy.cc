#include "learner/family/family_policy.h"

#include <cmath>

namespace modskill::learner::family {
namespace {

torch::nn::Sequential Mlp(int64_t in, const std::vector<int64_t>& hidden, int64_t out, double last_gain) {
  torch::nn::Sequential mlp;
  for (int64_t width : hidden) {
    mlp->push_back(torch::nn::Linear(in, width));
    mlp->push_back(torch::nn::ReLU());
    in = width;
  }
  torch::nn::Linear last(in, out);
  // A small last layer: the first actions sit near 0 (the clip's own pose and pace).
  torch::NoGradGuard no_grad;
  last->weight.mul_(last_gain);
  last->bias.zero_();
  mlp->push_back(last);
  return mlp;
}

}  // namespace

FamilyActorCriticImpl::FamilyActorCriticImpl(const FamilyPolicyConfig& config) : config_(config) {
  obs_norm_ = register_module("obs_norm", RunningMeanStd(config.obs_size));
  policy_ = register_module("policy", Mlp(config.obs_size, config.policy_hidden, config.action_size, 0.01));
  value_ = register_module("value", Mlp(config.obs_size, config.value_hidden, 1, 1.0));
  log_std_ = register_parameter("log_std", torch::full({config.action_size}, config.initial_log_std));
}

torch::Tensor FamilyActorCriticImpl::Mean(const torch::Tensor& obs) { return policy_->forward(obs_norm_->Normalize(obs)); }

torch::Tensor FamilyActorCriticImpl::Value(const torch::Tensor& obs) {
  return value_->forward(obs_norm_->Normalize(obs)).squeeze(-1);
}

torch::Tensor FamilyActorCriticImpl::LogProb(const torch::Tensor& mean, const torch::Tensor& actions) const {
  const torch::Tensor z = (actions - mean) * torch::exp(-log_std_);
  return (-0.5 * z.pow(2) - log_std_ - 0.5 * std::log(2 * M_PI)).sum(-1);
}

torch::Tensor FamilyActorCriticImpl::Entropy(int64_t batch) const {
  return (log_std_ + 0.5 * (1.0 + std::log(2 * M_PI))).sum().expand({batch});
}

}  // namespace modskill::learner::family
