// A learning rate steered by the policy's KL divergence per minibatch step (the schedule of
// rsl_rl, used by legged_gym and its descendants): after each step, a KL above twice the target
// divides the rate by 1.5 and a KL below half of it multiplies the rate by 1.5, within bounds.
// PPO's clipping alone does not bound how far a policy moves when a batch is small and the action
// has many dimensions: the family trainer's approx KL grew from 0.10 to 0.3-0.8 per update at a
// fixed 3e-4, and its rollouts changed from one iteration to the next.
#ifndef MODSKILL_LEARNER_KL_ADAPTIVE_LEARNING_RATE_H_
#define MODSKILL_LEARNER_KL_ADAPTIVE_LEARNING_RATE_H_

#include <torch/torch.h>

namespace modskill::learner {

class KlAdaptiveLearningRate {
 public:
  static constexpr double kFactor = 1.5;
  static constexpr double kMinRate = 1e-6, kMaxRate = 1e-2;

  // target_kl > 0 steers the rate; target_kl == 0 keeps `rate` fixed.
  KlAdaptiveLearningRate(double rate, double target_kl);

  double rate() const { return rate_; }
  double target_kl() const { return target_kl_; }
  // Restores a saved rate (clamped into the bounds).
  void set_rate(double rate);
  // After a minibatch step whose KL from the behaviour policy was `kl`; returns the new rate.
  double Update(double kl);
  // Writes the rate into every parameter group of an Adam optimizer.
  void ApplyTo(torch::optim::Adam& optimizer) const;

 private:
  double rate_, target_kl_;
};

// KL(old || new) per sample from log-probabilities, Schulman's low-variance estimator
// (r - 1) - log r with r = exp(new - old): never negative, unlike mean(old - new). Shape [B] -> [].
torch::Tensor EstimateKl(const torch::Tensor& log_probs, const torch::Tensor& old_log_probs);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_KL_ADAPTIVE_LEARNING_RATE_H_
