// ModSkill's policy: skill attention turns each part's observation into a skill embedding z_k,
// and one low-level controller per part maps [z_k, part k's observation] (or, with
// ControllerInput::kProprioception, [z_k, part k's proprioception]) to the means of part k's actions. A Gaussian with a fixed diagonal sigma (log_std, not trained) around the means.
#ifndef MODSKILL_LEARNER_MODSKILL_POLICY_H_
#define MODSKILL_LEARNER_MODSKILL_POLICY_H_

#include <vector>

#include <torch/torch.h>

#include "learner/model_config.h"
#include "learner/part_controller.h"
#include "learner/skill_attention.h"

namespace modskill::learner {

// Submodules: "attention" (SkillAttention), "controller<p>" per part, or one "whole_body_controller"
// for the whole-body ablation (input: all z flattened + the full obs, output: all actions).
// Buffer "log_std" [action_size], filled with config.log_std.
class ModSkillPolicyImpl : public torch::nn::Module {
 public:
  ModSkillPolicyImpl(const NetworkLayout& layout, const ModelConfig& config);

  // normalized_obs: [B, obs_size] -> action means: [B, action_size], in action order.
  torch::Tensor forward(const torch::Tensor& normalized_obs);

  // normalized_obs: [B, obs_size] -> z [B, P, E], attention [B, P, P]
  SkillAttentionOutput skills(const torch::Tensor& normalized_obs);

  // What part p's controller reads beside z_p (config.controller_input): [B, part obs] or
  // [B, the part's proprioceptive features].
  torch::Tensor ControllerState(const torch::Tensor& normalized_obs, size_t part_index) const;
  bool proprioceptive() const { return config_.controller_input == ModelConfig::ControllerInput::kProprioception; }

  // Diagonal Gaussian log-density: mean, actions [..., A], log_std [A] (or broadcastable) -> [...],
  // summed over the last dim.
  static torch::Tensor LogProb(const torch::Tensor& mean, const torch::Tensor& log_std, const torch::Tensor& actions);

  const NetworkLayout& layout() const { return layout_; }
  const ModelConfig& config() const { return config_; }
  const SkillAttention& attention() const { return attention_; }
  // One per part, or one for the whole body.
  const std::vector<PartController>& controllers() const { return controllers_; }
  const torch::Tensor& log_std() const { return log_std_; }

 private:
  NetworkLayout layout_;
  ModelConfig config_;
  SkillAttention attention_;
  std::vector<PartController> controllers_;
  torch::Tensor log_std_;
};
TORCH_MODULE(ModSkillPolicy);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_MODSKILL_POLICY_H_
