#include "learner/amp_loss.h"

namespace modskill::learner {

AmpLossTerms ComputeAmpLoss(const torch::Tensor& expert_logits, const torch::Tensor& policy_logits,
                            const torch::Tensor& gradient_penalty,
                            double gradient_penalty_weight) {
  AmpLossTerms terms;
  // Eq. 6: least-squares GAN with expert target +1 and policy target -1.
  terms.expert_loss = 0.5 * (expert_logits - 1.0).pow(2).mean();
  terms.policy_loss = 0.5 * (policy_logits + 1.0).pow(2).mean();
  terms.gradient_penalty = gradient_penalty.defined()
                               ? gradient_penalty
                               : torch::zeros({}, expert_logits.options());
  // Eq. 8: plus the weighted gradient penalty on expert samples.
  terms.total =
      terms.expert_loss + terms.policy_loss + gradient_penalty_weight * terms.gradient_penalty;
  torch::NoGradGuard no_grad;
  terms.expert_logit_mean = expert_logits.mean();
  terms.policy_logit_mean = policy_logits.mean();
  return terms;
}

torch::Tensor AmpReward(const torch::Tensor& logits) {
  torch::NoGradGuard no_grad;
  // Eq. 7: r = max(0, 1 - 0.25 * (D - 1)^2).
  return (1.0 - 0.25 * (logits - 1.0).pow(2)).clamp_min(0.0);
}

}  // namespace modskill::learner
