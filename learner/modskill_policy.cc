#include "learner/modskill_policy.h"

#include <cmath>
#include <string>

namespace modskill::learner {
namespace {

// Whether the parts observe a reference beside their self features (tracking, and the goal tasks'
// anchored base motion), so that a tracker's attention can read them.
bool PartsObserveAReference(const NetworkLayout& layout) {
  for (const PartSlices& part : layout.parts) {
    if (part.self_obs_size() != part.obs_size) return true;
  }
  return false;
}

}  // namespace

ModSkillPolicyImpl::ModSkillPolicyImpl(const NetworkLayout& layout, const ModelConfig& config)
    : layout_(layout), config_(config) {
  const int64_t num_parts = static_cast<int64_t>(layout.parts.size());
  const int64_t embed = config.embed_dim;
  if (task_mode()) {
    const absl::Status valid = layout.Validate();
    TORCH_CHECK(valid.ok(), "ModSkillPolicy: ", valid.ToString());
    TORCH_CHECK(embed > 0, "ModSkillPolicy: embed_dim is ", embed);
    TORCH_CHECK(proprioceptive() && !config.whole_body, "ModSkillPolicy: task '", layout.task,
                "' needs per-part proprioceptive controllers (skills of a tracker trained with --controller_input "
                "proprioception)");
    task_head_ = register_module("task_head", Mlp(layout.obs_size, config.task_hidden, num_parts * embed,
                                                  Activation::kElu));
    if (config.task_skill_prior && PartsObserveAReference(layout)) {
      // The tracker's attention (SkillLibrary loads and freezes it). The head starts near zero,
      // so the first policy plays the base motion with the tracker's skills.
      attention_ = register_module("attention", SkillAttention(layout, config));
      torch::NoGradGuard no_grad;
      const auto& last = task_head_->layers().back();
      last->weight.mul_(0.01);
      last->bias.zero_();
    }
  } else {
    // SkillAttention validates the layout.
    attention_ = register_module("attention", SkillAttention(layout, config));
  }
  // The parts' action slices tile [0, action_size) in part order, so concatenating the parts'
  // means gives the actions in action order.
  if (config.whole_body) {
    controllers_.push_back(register_module(
        "whole_body_controller",
        PartController(num_parts * embed + layout.obs_size, layout.action_size, config.controller_hidden)));
  } else {
    int64_t next_action = 0;
    for (int64_t p = 0; p < num_parts; ++p) {
      const PartSlices& part = layout.parts[p];
      TORCH_CHECK(part.action_start == next_action, "ModSkillPolicy: part '", part.name,
                  "' actions are not contiguous in part order");
      next_action += part.action_size;
      const int64_t state_size = proprioceptive() ? part.self_obs_size() : part.obs_size;
      TORCH_CHECK(state_size > 0, "ModSkillPolicy: part '", part.name,
                  "' has no proprioceptive features for its controller (the server describes none)");
      controllers_.push_back(register_module("controller" + std::to_string(p),
                                             PartController(embed + state_size, part.action_size,
                                                            config.controller_hidden)));
    }
    TORCH_CHECK(next_action == layout.action_size, "ModSkillPolicy: part actions do not cover action_size");
  }
  log_std_ = register_buffer("log_std",
                             torch::full({sample_size()}, task_mode() ? config.task_log_std : config.log_std));
}

int64_t ModSkillPolicyImpl::sample_size() const {
  return task_mode() ? static_cast<int64_t>(layout_.parts.size()) * config_.embed_dim : layout_.action_size;
}

SkillAttentionOutput ModSkillPolicyImpl::skills(const torch::Tensor& normalized_obs) {
  if (!task_mode()) return attention_->forward(normalized_obs);
  return {TaskZ(normalized_obs, task_head_->forward(normalized_obs)), torch::Tensor()};
}

torch::Tensor ModSkillPolicyImpl::TaskZ(const torch::Tensor& normalized_obs, const torch::Tensor& sample) {
  const int64_t num_parts = static_cast<int64_t>(layout_.parts.size());
  torch::Tensor z = sample.view({-1, num_parts, config_.embed_dim});
  if (uses_skill_prior()) z = attention_->forward(normalized_obs).z + z;
  return SkillAttentionImpl::NormalizeToSphere(z);
}

torch::Tensor ModSkillPolicyImpl::forward(const torch::Tensor& normalized_obs) {
  return ControllerActions(normalized_obs, skills(normalized_obs).z);
}

torch::Tensor ModSkillPolicyImpl::SampleMean(const torch::Tensor& normalized_obs) {
  return task_mode() ? task_head_->forward(normalized_obs) : forward(normalized_obs);
}

torch::Tensor ModSkillPolicyImpl::ActionsFor(const torch::Tensor& normalized_obs, const torch::Tensor& sample) {
  if (!task_mode()) return sample;
  return ControllerActions(normalized_obs, TaskZ(normalized_obs, sample));
}

torch::Tensor ModSkillPolicyImpl::ControllerActions(const torch::Tensor& normalized_obs, const torch::Tensor& z) {
  if (config_.whole_body) {
    return controllers_[0]->forward(torch::cat({z.flatten(1), normalized_obs}, 1));  // [B, A]
  }
  std::vector<torch::Tensor> means;
  for (size_t p = 0; p < controllers_.size(); ++p) {
    means.push_back(controllers_[p]->forward(torch::cat({z.select(1, p), ControllerState(normalized_obs, p)}, 1)));
  }
  return torch::cat(means, 1);  // [B, A]
}

torch::Tensor ModSkillPolicyImpl::ControllerState(const torch::Tensor& normalized_obs, size_t part_index) const {
  const PartSlices& part = layout_.parts[part_index];
  if (!proprioceptive()) return normalized_obs.slice(1, part.obs_start, part.obs_start + part.obs_size);
  std::vector<torch::Tensor> slices;
  for (const auto& [start, size] : part.self_obs) slices.push_back(normalized_obs.slice(1, start, start + size));
  return torch::cat(slices, 1);  // [B, self features of the part]
}

torch::Tensor ModSkillPolicyImpl::LogProb(const torch::Tensor& mean, const torch::Tensor& log_std,
                                          const torch::Tensor& actions, const torch::Tensor& sampled_dims) {
  static const double kHalfLog2Pi = 0.5 * std::log(2.0 * M_PI);
  const torch::Tensor scaled = (actions - mean) * torch::exp(-log_std);
  const torch::Tensor per_dim = -0.5 * scaled.square() - log_std - kHalfLog2Pi;
  return (sampled_dims.defined() ? per_dim * sampled_dims : per_dim).sum(-1);
}

}  // namespace modskill::learner
