#include "learner/ppo_loss.h"

namespace modskill::learner {

PpoLossTerms ComputePpoLoss(const torch::Tensor& new_log_prob, const torch::Tensor& old_log_prob,
                            const torch::Tensor& advantages, const torch::Tensor& new_values,
                            const torch::Tensor& old_values, const torch::Tensor& returns,
                            double clip_ratio, double value_clip, double value_coefficient) {
  TORCH_CHECK(new_log_prob.sizes() == old_log_prob.sizes() &&
                  new_log_prob.sizes() == advantages.sizes(),
              "ComputePpoLoss: new_log_prob ", new_log_prob.sizes(), ", old_log_prob ",
              old_log_prob.sizes(), " and advantages ", advantages.sizes(), " must agree");
  TORCH_CHECK(new_values.sizes() == old_values.sizes() && new_values.sizes() == returns.sizes(),
              "ComputePpoLoss: new_values ", new_values.sizes(), ", old_values ",
              old_values.sizes(), " and returns ", returns.sizes(), " must agree");
  const torch::Tensor adv = advantages.detach();
  const torch::Tensor log_ratio = new_log_prob - old_log_prob.detach();
  const torch::Tensor ratio = log_ratio.exp();  // rho_t(theta) = pi / pi_old

  // Eq. 7: L^CLIP = E[min(rho A, clip(rho, 1 - eps, 1 + eps) A)], maximized, so negated.
  const torch::Tensor unclipped = ratio * adv;
  const torch::Tensor clipped = ratio.clamp(1.0 - clip_ratio, 1.0 + clip_ratio) * adv;
  PpoLossTerms terms;
  terms.policy_loss = -torch::min(unclipped, clipped).mean();

  // Value loss: the pessimistic max of the unclipped and clipped squared errors.
  const torch::Tensor ret = returns.detach();
  const torch::Tensor value_error = (new_values - ret).pow(2);
  if (value_clip > 0.0) {
    const torch::Tensor old_v = old_values.detach();
    const torch::Tensor v_clipped = old_v + (new_values - old_v).clamp(-value_clip, value_clip);
    terms.value_loss = 0.5 * torch::max(value_error, (v_clipped - ret).pow(2)).mean();
  } else {
    terms.value_loss = 0.5 * value_error.mean();
  }

  // Eq. 9 without the entropy term: minimize -L^CLIP + c1 * L^VF.
  terms.total = terms.policy_loss + value_coefficient * terms.value_loss;

  torch::NoGradGuard no_grad;
  terms.approx_kl = (-log_ratio).mean();
  terms.clip_fraction = ((ratio - 1.0).abs() > clip_ratio).to(torch::kFloat).mean();
  return terms;
}

torch::Tensor NormalizeAdvantages(const torch::Tensor& a) {
  torch::NoGradGuard no_grad;
  return (a - a.mean()) / (a.std(/*unbiased=*/false) + 1e-8);
}

torch::Tensor DecoupledAdvantages(const torch::Tensor& advantages, const torch::Tensor& proximal_log_prob,
                                  const torch::Tensor& behaviour_log_prob, double max_weight) {
  torch::NoGradGuard no_grad;
  const torch::Tensor weight = torch::exp(proximal_log_prob - behaviour_log_prob).clamp_max(max_weight);
  return advantages.detach() * weight;
}

}  // namespace modskill::learner
