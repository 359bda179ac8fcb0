// PPO's loss (Schulman et al. 2017, "Proximal Policy Optimization Algorithms"): the clipped
// surrogate (eq. 7) plus a clipped value loss, combined as in eq. 9 without the entropy
// bonus (the caller adds it, since only the caller knows the action distribution).
#ifndef MODSKILL_LEARNER_PPO_LOSS_H_
#define MODSKILL_LEARNER_PPO_LOSS_H_

#include <torch/torch.h>

namespace modskill::learner {

// Scalar tensors. `total`, `policy_loss` and `value_loss` carry gradients; `approx_kl` and
// `clip_fraction` are detached diagnostics.
struct PpoLossTerms {
  torch::Tensor total;          // policy_loss + value_coefficient * value_loss
  torch::Tensor policy_loss;    // -mean(min(rho * A, clip(rho, 1 - eps, 1 + eps) * A))
  torch::Tensor value_loss;     // 0.5 * mean(max((V - R)^2, (V_clipped - R)^2))
  torch::Tensor approx_kl;      // mean(old_log_prob - new_log_prob)
  torch::Tensor clip_fraction;  // fraction of samples with |rho - 1| > eps
};

// All inputs are [B] (any shape works as long as all agree). `advantages` are used as given:
// normalize them first (NormalizeAdvantages) if wanted. `old_log_prob`, `advantages`,
// `old_values` and `returns` are treated as constants (detached).
// V_clipped = old_values + clamp(new_values - old_values, -value_clip, value_clip);
// value_clip <= 0 turns value clipping off (plain 0.5 * mean((V - R)^2)).
PpoLossTerms ComputePpoLoss(const torch::Tensor& new_log_prob, const torch::Tensor& old_log_prob,
                            const torch::Tensor& advantages, const torch::Tensor& new_values,
                            const torch::Tensor& old_values, const torch::Tensor& returns,
                            double clip_ratio, double value_clip, double value_coefficient);

// Decoupled PPO (Hilton et al. 2021, "Batch size-invariance for policy optimization") for a batch
// collected by older weights (the behaviour policy): the clipping is centred on the weights the
// update starts from (the proximal policy; pass its log-probabilities as ComputePpoLoss's
// old_log_prob), and each advantage is importance-weighted by pi_prox / pi_behaviour, truncated at
// max_weight (V-trace's rho-bar, Espeholt et al. 2018) so that one stale action cannot dominate.
// Returns the weighted advantages, detached.
torch::Tensor DecoupledAdvantages(const torch::Tensor& advantages, const torch::Tensor& proximal_log_prob,
                                  const torch::Tensor& behaviour_log_prob, double max_weight = 1.0);

// (a - mean(a)) / (std(a) + 1e-8), with the population standard deviation, so a single
// element normalizes to 0 rather than NaN. Detached.
torch::Tensor NormalizeAdvantages(const torch::Tensor& a);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_PPO_LOSS_H_
