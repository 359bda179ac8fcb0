#include "server/core/env/policy_fit.h"

#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace modskill {

PolicySpec PolicySpecForEnv(const EnvSpec& spec) {
  PolicySpec policy;
  policy.part_layout = spec.layout.name;
  policy.obs_size = spec.obs_size;
  policy.action_size = spec.action_size;
  policy.joint_names = spec.joint_names;
  policy.control_dt = spec.control_dt;
  policy.physics = spec.physics;
  policy.task = TaskInfoOf(spec.task).name;
  policy.reference_frames = spec.reference_frames;
  return policy;
}

absl::Status CheckPolicyFitsEnv(const PolicySpec& policy, const EnvSpec& server, absl::string_view env_task) {
  auto mismatch = [](absl::string_view field, const auto& mine, const auto& theirs) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: trained with ", field, " = ", mine,
                                                      ", this server has ", theirs));
  };
  if (policy.task != env_task) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: a policy for task ", policy.task, ", this env runs ",
                                                      env_task, " (a task policy runs in a session of its task: ",
                                                      "modskill-learner --eval --task ", policy.task, ")"));
  }
  if (policy.part_layout != server.layout.name) return mismatch("part_layout", policy.part_layout, server.layout.name);
  if (policy.obs_size != server.obs_size) return mismatch("obs_size", policy.obs_size, server.obs_size);
  if (policy.action_size != server.action_size) return mismatch("action_size", policy.action_size, server.action_size);
  if (std::abs(policy.control_dt - server.control_dt) > 1e-9) return mismatch("control_dt", policy.control_dt, server.control_dt);
  if (std::string difference = PhysicsDifference(policy.physics, server.physics, "this server's"); !difference.empty()) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: trained with ", difference));
  }
  if (policy.joint_names != server.joint_names) {
    return absl::FailedPreconditionError("checkpoint: trained with another joint order (joint_names differ)");
  }
  return absl::OkStatus();
}

}  // namespace modskill
