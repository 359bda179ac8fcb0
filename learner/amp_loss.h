// AMP's least-squares discriminator loss and style reward (Peng et al. 2021, "AMP:
// Adversarial Motion Priors for Stylized Physics-Based Character Control", eq. 6-8).
// Network-agnostic: the discriminator and its gradient penalty are computed by the caller.
#ifndef MODSKILL_LEARNER_AMP_LOSS_H_
#define MODSKILL_LEARNER_AMP_LOSS_H_

#include <torch/torch.h>

namespace modskill::learner {

// Scalar tensors. `total`, `expert_loss`, `policy_loss` and `gradient_penalty` carry
// gradients; the logit means are detached diagnostics.
struct AmpLossTerms {
  torch::Tensor total;              // expert_loss + policy_loss + w_gp * gradient_penalty
  torch::Tensor expert_loss;        // 0.5 * mean((D(expert) - 1)^2), target +1
  torch::Tensor policy_loss;        // 0.5 * mean((D(policy) + 1)^2), target -1
  torch::Tensor gradient_penalty;   // as passed in
  torch::Tensor expert_logit_mean;  // mean(D(expert))
  torch::Tensor policy_logit_mean;  // mean(D(policy))
};

// expert_logits [B_e] or [B_e, 1], policy_logits [B_p] or [B_p, 1]: raw discriminator outputs.
// gradient_penalty: a scalar (e.g. mean ||grad_x D(x_expert)||^2); an undefined tensor counts
// as 0.
// total = 0.5 * (mean((d_e - 1)^2) + mean((d_p + 1)^2)) + gradient_penalty_weight * gp.
AmpLossTerms ComputeAmpLoss(const torch::Tensor& expert_logits, const torch::Tensor& policy_logits,
                            const torch::Tensor& gradient_penalty,
                            double gradient_penalty_weight);

// Style reward (eq. 7): max(0, 1 - 0.25 * (d - 1)^2), same shape as `logits`, no gradient.
// d = 1 (looks like the expert) -> 1; d <= -1 or d >= 3 -> 0.
torch::Tensor AmpReward(const torch::Tensor& logits);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_AMP_LOSS_H_
