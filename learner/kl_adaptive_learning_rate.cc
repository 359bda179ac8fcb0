#include "learner/kl_adaptive_learning_rate.h"

#include <algorithm>

#include "learner/learning_rate_decay.h"

namespace modskill::learner {

KlAdaptiveLearningRate::KlAdaptiveLearningRate(double rate, double target_kl)
    : rate_(std::clamp(rate, kMinRate, kMaxRate)), target_kl_(target_kl) {}

void KlAdaptiveLearningRate::set_rate(double rate) { rate_ = std::clamp(rate, kMinRate, kMaxRate); }

double KlAdaptiveLearningRate::Update(double kl) {
  if (target_kl_ <= 0) return rate_;
  if (kl > 2 * target_kl_) set_rate(rate_ / kFactor);
  if (kl < 0.5 * target_kl_) set_rate(rate_ * kFactor);
  return rate_;
}

void KlAdaptiveLearningRate::ApplyTo(torch::optim::Adam& optimizer) const { SetLearningRate(optimizer, rate_); }

torch::Tensor EstimateKl(const torch::Tensor& log_probs, const torch::Tensor& old_log_probs) {
  torch::NoGradGuard no_grad;
  const torch::Tensor log_ratio = log_probs - old_log_probs;
  return (torch::exp(log_ratio) - 1 - log_ratio).mean();
}

}  // namespace modskill::learner
