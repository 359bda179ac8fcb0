// ModSkill's policy: skill attention turns each part's observation into a skill embedding z_k,
// and one low-level controller per part maps [z_k, part k's observation] (or, with
// ControllerInput::kProprioception, [z_k, part k's proprioception]) to the means of part k's
// actions. A Gaussian with a fixed diagonal sigma (log_std, not trained) around the means.
//
// Skill reuse (a layout with a goal, NetworkLayout::has_goal): a task head replaces the attention
// and maps the task observation to one z per part for the (frozen, proprioceptive) controllers
// of a tracker (skill_library.h). Exploration then happens in z space, as in ASE's and PULSE's
// high levels: PPO samples the task head's raw output and the controllers turn the sample into
// actions. SampleMean, ActionsFor and sample_size say what is sampled in either mode. With a
// skill prior (uses_skill_prior) the tracker's frozen attention gives z_prior and the sample is a
// displacement of it: z = normalize(z_prior + sample).
#ifndef MODSKILL_LEARNER_MODSKILL_POLICY_H_
#define MODSKILL_LEARNER_MODSKILL_POLICY_H_

#include <vector>

#include <torch/torch.h>

#include "learner/model_config.h"
#include "learner/part_controller.h"
#include "learner/skill_attention.h"

namespace modskill::learner {

// Submodules: "attention" (SkillAttention) or, with a goal, "task_head" (Mlp: obs_size ->
// config.task_hidden... -> P * E) and, with a skill prior, the tracker's "attention" as well; "controller<p>" per part, or one "whole_body_controller" for
// the whole-body ablation (input: all z flattened + the full obs, output: all actions).
// Buffer "log_std" [sample_size()], filled with config.log_std (config.task_log_std with a goal).
class ModSkillPolicyImpl : public torch::nn::Module {
 public:
  ModSkillPolicyImpl(const NetworkLayout& layout, const ModelConfig& config);

  // normalized_obs: [B, obs_size] -> deterministic action means: [B, action_size], in action
  // order (with a goal: the controllers on normalize(task head output)).
  torch::Tensor forward(const torch::Tensor& normalized_obs);

  // What PPO samples, and its mean: [B, obs_size] -> [B, sample_size()]. Tracking: the action
  // means (forward). With a goal: the task head's raw output, [B, P * E].
  torch::Tensor SampleMean(const torch::Tensor& normalized_obs);
  // The actions a sample [B, sample_size()] sends: the sample itself in tracking; with a goal the
  // controllers on z = normalize(sample viewed [B, P, E]).
  torch::Tensor ActionsFor(const torch::Tensor& normalized_obs, const torch::Tensor& sample);
  int64_t sample_size() const;
  bool task_mode() const { return layout_.has_goal(); }
  // A task policy over the tracker's attention (config.task_skill_prior where the layout's parts
  // observe a reference: the parts' obs slices hold more than their self features).
  bool uses_skill_prior() const { return task_mode() && !attention_.is_empty(); }
  // The z a sample [B, sample_size()] drives in task mode: normalize(sample), or with a prior
  // normalize(z_prior(obs) + sample). [B, P, E]
  torch::Tensor TaskZ(const torch::Tensor& normalized_obs, const torch::Tensor& sample);

  // normalized_obs: [B, obs_size] -> z [B, P, E], attention [B, P, P] (undefined with a goal)
  SkillAttentionOutput skills(const torch::Tensor& normalized_obs);
  // The per-part controllers on z [B, P, E] -> action means [B, action_size].
  torch::Tensor ControllerActions(const torch::Tensor& normalized_obs, const torch::Tensor& z);

  // What part p's controller reads beside z_p (config.controller_input): [B, part obs] or
  // [B, the part's proprioceptive features].
  torch::Tensor ControllerState(const torch::Tensor& normalized_obs, size_t part_index) const;
  bool proprioceptive() const { return config_.controller_input == ModelConfig::ControllerInput::kProprioception; }

  // Diagonal Gaussian log-density: mean, actions [..., A], log_std [A] (or broadcastable) -> [...],
  // summed over the last dim; with `sampled_dims` ([A], 1 or 0) over the dims marked 1 only (the
  // others act on their mean and carry no probability).
  static torch::Tensor LogProb(const torch::Tensor& mean, const torch::Tensor& log_std, const torch::Tensor& actions,
                               const torch::Tensor& sampled_dims = {});

  const NetworkLayout& layout() const { return layout_; }
  const ModelConfig& config() const { return config_; }
  // Null with a goal, unless it is the tracker's attention under a skill prior.
  const SkillAttention& attention() const { return attention_; }
  // Null without a goal.
  const Mlp& task_head() const { return task_head_; }
  // One per part, or one for the whole body.
  const std::vector<PartController>& controllers() const { return controllers_; }
  const torch::Tensor& log_std() const { return log_std_; }

 private:
  NetworkLayout layout_;
  ModelConfig config_;
  SkillAttention attention_{nullptr};
  Mlp task_head_{nullptr};
  std::vector<PartController> controllers_;
  torch::Tensor log_std_;
};
TORCH_MODULE(ModSkillPolicy);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_MODSKILL_POLICY_H_
