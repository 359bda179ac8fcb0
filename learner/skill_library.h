// The skills a task policy reuses (skill reuse, issue 13): the part controllers of a tracker
// trained with --controller_input proprioception, read from its exported policy.pt, its skill
// attention (the prior of steer, reach and strike, model_config.h task_skill_prior) and the
// observation statistics they were trained under. The task policy's controllers and attention
// are these weights, frozen; its normalizer sees the tracker's features exactly as the tracker's
// did.
#ifndef MODSKILL_LEARNER_SKILL_LIBRARY_H_
#define MODSKILL_LEARNER_SKILL_LIBRARY_H_

#include <string>
#include <vector>

#include <torch/torch.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/policy_import.h"
#include "learner/running_mean_std.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

class SkillLibrary {
 public:
  // INVALID_ARGUMENT naming the file when it is not a policy file, is itself a task policy, or
  // has no per-part controllers (an affine or whole-body policy).
  static absl::StatusOr<SkillLibrary> Load(const std::string& path);

  // FAILED_PRECONDITION naming the file unless the tracker fits the server: `tracking` is
  // Describe's spec for the session's part layout, `task` the task session's spec. Its layout,
  // parts, joints and observation size must be theirs, and each controller must read z and its
  // bodies' self features only (a part_obs tracker's controllers read the reference).
  absl::Status CheckFits(const v1::EnvSpec& tracking, const v1::EnvSpec& task) const;

  // `config` with the tracker's embed_dim and controller sizes, per-part proprioceptive controllers.
  ModelConfig ConfigFor(ModelConfig config) const;
  // Copies the controllers (and, under a skill prior, the attention) into `policy` (a task policy
  // built with ConfigFor) and freezes them (requires_grad false: the optimizer leaves them out,
  // ppo_update.h).
  absl::Status LoadControllers(ModSkillPolicyImpl& policy) const;
  // Copies the tracker's mean and var of what it observed into `norm` and freezes those dims; the
  // goal dims keep adapting. Where the task observes a reference (its parts' slices are
  // tracking's), the whole tracking observation; otherwise every body's self features, from
  // tracking's self_obs slices to the task's, body by body.
  absl::Status LoadSelfStatistics(const v1::EnvSpec& tracking, const v1::EnvSpec& task, RunningMeanStdImpl& norm) const;

  // FAILED_PRECONDITION naming the file unless `policy`'s controllers are these skills, weight
  // for weight (a task policy evaluated beside the skills it was trained on).
  absl::Status CheckSameControllers(const ModSkillPolicyImpl& policy) const;

  const std::string& path() const { return policy_.path; }
  const PolicySpec& spec() const { return policy_.spec; }  // the tracker's
  int64_t embed_dim() const { return embed_dim_; }
  const std::vector<int64_t>& controller_hidden() const { return controller_hidden_; }
  size_t num_parts() const { return controllers_.size(); }

 private:
  // The error for a file that does not fit: FAILED_PRECONDITION naming it and `why`.
  absl::Status Misfit(const std::string& why) const;
  absl::Status CheckControllerInputs(const v1::EnvSpec& tracking) const;
  absl::Status LoadAttention(SkillAttentionImpl& attention) const;

  ExportedPolicy policy_;
  int64_t embed_dim_ = 0;
  std::vector<int64_t> controller_hidden_;
  std::vector<std::vector<LinearWeights>> controllers_;  // per part
  // The attention's shape (its maps are copied from policy_ when a task policy loads them).
  bool has_attention_ = false;
  std::vector<int64_t> attention_hidden_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_SKILL_LIBRARY_H_
