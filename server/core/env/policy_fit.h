// A policy file against the env it is asked to drive: the spec a policy trained on this env
// records, and the check that a loaded policy's spec matches the server's env.
#ifndef MODSKILL_SERVER_CORE_ENV_POLICY_FIT_H_
#define MODSKILL_SERVER_CORE_ENV_POLICY_FIT_H_

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "common/policy/policy_spec.h"
#include "server/core/env/env_spec.h"

namespace modskill {

// The env's task, layout, sizes, joint order, control step and physics; the action mapping and the
// controller input left at their defaults.
PolicySpec PolicySpecForEnv(const EnvSpec& spec);

// FAILED_PRECONDITION naming the first difference (task, layout, sizes, control step, physics
// when the policy records it, joint order). `env_task` is the task the env runs (PolicySpec::task; Rollout runs tracking); the task
// comes first, since a task policy's observation size differs from a tracker's anyway.
absl::Status CheckPolicyFitsEnv(const PolicySpec& policy, const EnvSpec& server,
                                absl::string_view env_task = kTrackingTask);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_POLICY_FIT_H_
