#include "learner/critic.h"

namespace modskill::learner {

CriticImpl::CriticImpl(int64_t obs_size, const std::vector<int64_t>& hidden, bool normalize_returns)
    : mlp_(register_module("mlp", Mlp(obs_size, hidden, 1, Activation::kElu))),
      return_norm_(register_module("return_norm", RunningMeanStd(1))),
      normalize_returns_(register_buffer("normalize_returns", torch::tensor(int64_t{normalize_returns ? 1 : 0}))) {}

torch::Tensor CriticImpl::NormalizedValue(const torch::Tensor& normalized_obs) {
  return mlp_->forward(normalized_obs).squeeze(-1);
}

torch::Tensor CriticImpl::forward(const torch::Tensor& normalized_obs) {
  const torch::Tensor value = NormalizedValue(normalized_obs);
  if (!normalizes_returns()) return value;
  const auto mean = return_norm_->mean().to(value.scalar_type());
  const auto std = (return_norm_->var() + RunningMeanStdImpl::kEpsilon).sqrt().to(value.scalar_type());
  return value * std + mean;
}

torch::Tensor CriticImpl::NormalizeReturns(const torch::Tensor& returns) const {
  if (!normalizes_returns()) return returns;
  const auto mean = return_norm_->mean().to(returns.scalar_type());
  const auto std = (return_norm_->var() + RunningMeanStdImpl::kEpsilon).sqrt().to(returns.scalar_type());
  return (returns - mean) / std;
}

void CriticImpl::load(torch::serialize::InputArchive& archive) {
  torch::serialize::InputArchive mlp;
  archive.read("mlp", mlp);
  mlp_->load(mlp);
  torch::serialize::InputArchive return_norm;
  torch::Tensor normalize_returns = torch::tensor(int64_t{0});
  if (archive.try_read("return_norm", return_norm)) return_norm_->load(return_norm);
  archive.try_read("normalize_returns", normalize_returns, /*is_buffer=*/true);
  torch::NoGradGuard no_grad;
  normalize_returns_.copy_(normalize_returns);
}

}  // namespace modskill::learner
