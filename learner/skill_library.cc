#include "learner/skill_library.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "common/wire/physics_wire.h"

namespace modskill::learner {
namespace {

constexpr char kRetrain[] = "; train the tracker with --controller_input proprioception";

int64_t SelfSize(const v1::BodyPart& part) {
  int64_t size = 0;
  for (const v1::Slice& self : part.self_obs()) size += self.size();
  return size;
}

// Whether the task's parts observe what tracking's do, at the same places (steer, reach and
// strike observe their anchored base motion as the reference).
bool ObservesTrackingsReference(const v1::EnvSpec& tracking, const v1::EnvSpec& task) {
  if (tracking.parts_size() != task.parts_size()) return false;
  for (int p = 0; p < task.parts_size(); ++p) {
    const v1::Slice &mine = tracking.parts(p).obs(), &theirs = task.parts(p).obs();
    if (mine.start() != theirs.start() || mine.size() != theirs.size()) return false;
  }
  return true;
}

}  // namespace

absl::StatusOr<SkillLibrary> SkillLibrary::Load(const std::string& path) {
  SkillLibrary library;
  auto policy = ReadExportedPolicy(path);
  if (!policy.ok()) return policy.status();
  library.policy_ = *std::move(policy);
  const PolicySpec& spec = library.policy_.spec;
  auto invalid = [&](const std::string& why) { return absl::InvalidArgumentError(absl::StrCat(path, ": ", why)); };
  if (spec.task != kTrackingTask) {
    return invalid(absl::StrCat("a policy for task ", spec.task, ", not a tracker (skills come from a tracking run's policy.pt)"));
  }
  if (spec.reference_frames > 1) {
    return invalid(absl::StrCat("a tracker observing ", spec.reference_frames,
                                " reference frames; a task's base motion shows its skills one (train them with "
                                "--reference_frames 1)"));
  }
  if (library.policy_.Has("whole_body_controller_fc0_weight")) {
    return invalid(absl::StrCat("one whole-body controller (--whole_body), no part controllers to reuse", kRetrain));
  }
  for (int p = 0; library.policy_.Has(absl::StrCat("part", p, "_controller_fc0_weight")); ++p) {
    auto layers = library.policy_.Mlp(absl::StrCat("part", p, "_controller"));
    if (!layers.ok()) return layers.status();
    if (p > 0 && HiddenSizes(*layers) != library.controller_hidden_) {
      return invalid(absl::StrCat("part ", p, "'s controller has other hidden sizes than part 0's"));
    }
    library.controller_hidden_ = HiddenSizes(*layers);
    library.controllers_.push_back(*std::move(layers));
  }
  if (library.controllers_.empty()) return invalid("not a ModSkill policy (no part<p>_controller weights)");
  // z's size: the output of part 0's value map (the attention's, present with or without attention).
  auto value = library.policy_.Mlp("part0_value");
  if (!value.ok()) return value.status();
  if (value->empty()) return invalid("not a ModSkill tracker (no part0_value weights: no skill embedding)");
  library.embed_dim_ = value->back().weight.size(0);
  library.attention_hidden_ = HiddenSizes(*value);
  library.has_attention_ = library.policy_.Has("part0_key_fc0_weight");
  for (size_t p = 0; p < library.controllers_.size(); ++p) {
    for (const char* map : {"value", "key", "query"}) {
      if (std::string(map) != "value" && !library.has_attention_) continue;
      auto layers = library.policy_.Mlp(absl::StrCat("part", p, "_", map));
      if (!layers.ok()) return layers.status();
      if (layers->empty()) return invalid(absl::StrCat("no part", p, "_", map, " weights (an incomplete attention)"));
    }
  }
  for (const char* name : {"obs_mean", "obs_var"}) {
    if (!library.policy_.Has(name) || library.policy_.tensors.at(name).numel() != spec.obs_size) {
      return invalid(absl::StrCat("no ", name, " of ", spec.obs_size, " features (not an exported ModSkill policy)"));
    }
  }
  return library;
}

absl::Status SkillLibrary::Misfit(const std::string& why) const {
  return absl::FailedPreconditionError(absl::StrCat("--skills ", path(), ": ", why));
}

absl::Status SkillLibrary::CheckFits(const v1::EnvSpec& tracking, const v1::EnvSpec& task) const {
  const PolicySpec& spec = policy_.spec;
  if (spec.part_layout != task.part_layout()) {
    return Misfit(absl::StrCat("trained with part layout ", spec.part_layout, ", the task session has ",
                               task.part_layout(), " (--part_layout)"));
  }
  if (num_parts() != static_cast<size_t>(task.parts_size()) || tracking.parts_size() != task.parts_size()) {
    return Misfit(absl::StrCat(num_parts(), " part controllers, the task session has ", task.parts_size(), " parts"));
  }
  if (spec.action_size != task.action_size() ||
      !std::equal(spec.joint_names.begin(), spec.joint_names.end(), task.joint_names().begin(),
                  task.joint_names().end())) {
    return Misfit(absl::StrCat("trained on ", spec.action_size, " joints, the task session has ", task.action_size(),
                               " or another joint order"));
  }
  if (std::abs(spec.control_dt - task.control_dt()) > 1e-9) {
    return Misfit(absl::StrCat("trained at control_dt ", spec.control_dt, ", the task session steps ", task.control_dt()));
  }
  if (std::string difference = PhysicsDifference(spec.physics, PhysicsOf(task), "the task session's");
      !difference.empty()) {
    return Misfit(absl::StrCat("trained with ", difference));
  }
  if (spec.obs_size != tracking.obs_size()) {
    return Misfit(absl::StrCat("trained on ", spec.obs_size, " observation features, this server's tracker sees ",
                               tracking.obs_size()));
  }
  for (int p = 0; p < task.parts_size(); ++p) {
    const v1::BodyPart &mine = tracking.parts(p), &theirs = task.parts(p);
    bool same = mine.self_obs_size() == theirs.self_obs_size() && mine.action().size() == theirs.action().size();
    for (int b = 0; same && b < mine.self_obs_size(); ++b) same = mine.self_obs(b).size() == theirs.self_obs(b).size();
    if (!same) return Misfit(absl::StrCat("part ", mine.name(), ": the task session describes other bodies or joints"));
  }
  return CheckControllerInputs(tracking);
}

// A controller reads [z, state]: the state is its bodies' self features (proprioception) or the
// part's whole observation (part_obs, the reference included). Read from the weights, so that
// files exported before the spec recorded controller_input are judged by what they are.
absl::Status SkillLibrary::CheckControllerInputs(const v1::EnvSpec& tracking) const {
  for (int p = 0; p < tracking.parts_size(); ++p) {
    const v1::BodyPart& part = tracking.parts(p);
    const int64_t state = controllers_[p].front().weight.size(1) - embed_dim_;
    const int64_t actions = controllers_[p].back().weight.size(0);
    if (state == part.obs().size() && state != SelfSize(part)) {
      return Misfit(absl::StrCat("trained with --controller_input part_obs: its controllers read the reference, ",
                                 "which a task session does not have", kRetrain));
    }
    if (state != SelfSize(part) || actions != part.action().size()) {
      return Misfit(absl::StrCat("part ", part.name(), "'s controller reads ", state, " features and drives ", actions,
                                 " joints; the server's part has ", SelfSize(part), " self features and ",
                                 part.action().size(), " joints"));
    }
  }
  return absl::OkStatus();
}

ModelConfig SkillLibrary::ConfigFor(ModelConfig config) const {
  config.embed_dim = embed_dim_;
  config.controller_hidden = controller_hidden_;
  config.controller_input = ModelConfig::ControllerInput::kProprioception;
  config.whole_body = false;
  config.attention_hidden = attention_hidden_;
  config.attention = has_attention_;
  return config;
}

absl::Status SkillLibrary::LoadControllers(ModSkillPolicyImpl& policy) const {
  if (!policy.task_mode() || policy.controllers().size() != num_parts()) {
    return absl::InvalidArgumentError(absl::StrCat("--skills ", path(), ": ", num_parts(),
                                                   " controllers do not fit a policy with ", policy.controllers().size()));
  }
  for (size_t p = 0; p < num_parts(); ++p) {
    PartController controller = policy.controllers()[p];
    Mlp mlp = controller->mlp();  // a handle that can be written through
    if (absl::Status status = CopyIntoMlp(controllers_[p], *mlp, absl::StrCat(path(), ": part ", p));
        !status.ok()) {
      return status;
    }
    for (torch::Tensor& parameter : controller->parameters()) parameter.set_requires_grad(false);
  }
  if (!policy.uses_skill_prior()) return absl::OkStatus();
  SkillAttention attention = policy.attention();  // a handle that can be written through
  return LoadAttention(*attention);
}

absl::Status SkillLibrary::LoadAttention(SkillAttentionImpl& attention) const {
  if (attention.values().size() != num_parts() || attention.uses_attention() != has_attention_) {
    return Misfit("its attention does not fit the task policy's (parts or attention maps differ)");
  }
  if (absl::Status status = CopyAttentionFrom(policy_, attention); !status.ok()) return status;
  for (torch::Tensor& parameter : attention.parameters()) parameter.set_requires_grad(false);
  return absl::OkStatus();
}

absl::Status SkillLibrary::CheckSameControllers(const ModSkillPolicyImpl& policy) const {
  bool same = policy.controllers().size() == num_parts();
  for (size_t p = 0; same && p < num_parts(); ++p) {
    const auto& layers = policy.controllers()[p]->mlp()->layers();
    same = layers.size() == controllers_[p].size();
    for (size_t i = 0; same && i < layers.size(); ++i) {
      same = layers[i]->weight.sizes().equals(controllers_[p][i].weight.sizes()) &&
             torch::equal(layers[i]->weight, controllers_[p][i].weight) &&
             torch::equal(layers[i]->bias, controllers_[p][i].bias);
    }
  }
  return same ? absl::OkStatus() : Misfit("not the skills this task policy drives (its controllers differ)");
}

absl::Status SkillLibrary::LoadSelfStatistics(const v1::EnvSpec& tracking, const v1::EnvSpec& task,
                                              RunningMeanStdImpl& norm) const {
  if (norm.size() != task.obs_size()) {
    return absl::InvalidArgumentError(absl::StrCat("normalizer of ", norm.size(), " features, task obs ", task.obs_size()));
  }
  torch::NoGradGuard no_grad;
  const torch::Tensor& mean = policy_.tensors.at("obs_mean");
  const torch::Tensor& var = policy_.tensors.at("obs_var");
  torch::Tensor frozen = torch::zeros({norm.size()}, torch::kBool);
  if (ObservesTrackingsReference(tracking, task)) {
    const int64_t size = tracking.obs_size();
    if (mean.numel() != size || size > norm.size()) return Misfit("its observation statistics do not fit the task's");
    norm.mean().narrow(0, 0, size).copy_(mean);
    norm.var().narrow(0, 0, size).copy_(var);
    frozen.narrow(0, 0, size).fill_(true);
    norm.FreezeDims(frozen);
    return absl::OkStatus();
  }
  for (int p = 0; p < task.parts_size(); ++p) {
    for (int b = 0; b < task.parts(p).self_obs_size(); ++b) {
      const v1::Slice &from = tracking.parts(p).self_obs(b), &to = task.parts(p).self_obs(b);
      if (from.size() != to.size() || from.start() + from.size() > mean.numel() || to.start() + to.size() > norm.size()) {
        return Misfit(absl::StrCat("part ", task.parts(p).name(), " body ", b, ": self features do not match"));
      }
      norm.mean().narrow(0, to.start(), to.size()).copy_(mean.narrow(0, from.start(), from.size()));
      norm.var().narrow(0, to.start(), to.size()).copy_(var.narrow(0, from.start(), from.size()));
      frozen.narrow(0, to.start(), to.size()).fill_(true);
    }
  }
  norm.FreezeDims(frozen);
  return absl::OkStatus();
}

}  // namespace modskill::learner
