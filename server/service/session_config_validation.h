// A Simulate stream's SessionConfig -> what the session runs with, every field checked before
// anything is allocated. The service and fuzz/simulate_request_fuzzer.cc share it, so the fuzzer
// sees exactly the checks a client's bytes meet.
#ifndef MODSKILL_SERVER_SERVICE_SESSION_CONFIG_VALIDATION_H_
#define MODSKILL_SERVER_SERVICE_SESSION_CONFIG_VALIDATION_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "modskill/v1/modskill.pb.h"
#include "server/core/env/action_mapping.h"
#include "server/core/env/tracking_env.h"
#include "server/core/sim/part_layout.h"

namespace modskill {

// A session config, checked.
struct SessionSettings {
  int num_envs = 0;
  uint64_t seed = 0;
  PartLayout layout;
  // termination, termination_distance, termination_bodies, action, max_episode_steps, task and
  // task_settings.
  TrackingEnvConfig env;
  int amp_frames = 0;  // AMP frames per step result: kAmpHistory, 1 or 0
};

// The checks in the order the service reports them: num_envs in [1, max_envs_per_session]
// (above: RESOURCE_EXHAUSTED), max_episode_steps >= 0, the layout (NOT_FOUND), termination,
// its distance, action mode and residual scale, termination bodies, amp_obs, the task and its
// settings, the family, reward_parts, reward_relative_to_root, imitation_kernels, no more motion names than max_library_clips (INVALID_ARGUMENT). The clip names themselves are left to the library.
absl::StatusOr<SessionSettings> ParseSessionConfig(const v1::SessionConfig& config, int max_envs_per_session,
                                                   int max_library_clips, const PartLayoutCatalog& layouts);

// The named layout, or the catalog's default for ""; NOT_FOUND for an unknown name.
absl::StatusOr<PartLayout> FindLayout(const PartLayoutCatalog& layouts, const std::string& name);

// TERMINATION_UNSPECIFIED means `default_mode` (TRAINING for sessions, EVALUATION for rollouts).
absl::StatusOr<TerminationMode> ToTermination(v1::TerminationMode mode, v1::TerminationMode default_mode);
// 0 means the mode's default (0.5 m in evaluation, 0.25 m otherwise).
absl::StatusOr<double> ToTerminationDistance(float distance, TerminationMode mode);
// 0 in a speed or interval field means its default, an unset reach_* field too; then
// TaskSettings::Validate.
absl::StatusOr<TaskSettings> ToTaskSettings(const v1::TaskSettings& wire);
// A family session's ranges (empty when SessionConfig.family is unset): offered parameters, valid
// ranges, one clip, task tracking, residual actions, no loop_clips; INVALID_ARGUMENT naming the
// field otherwise.
absl::StatusOr<std::vector<ParamRange>> ToFamilyRanges(const v1::SessionConfig& config, ActionMode action_mode,
                                                       TaskKind task);
// The energy penalty's coefficient: the paper's x SessionConfig.energy_weight (unset: 1);
// INVALID_ARGUMENT naming energy_weight outside [0, 100] or non-zero in a family session.
absl::StatusOr<double> ToEnergyCoefficient(const v1::SessionConfig& config, bool family);
// loop_clips and anchor_reference in tracking only, anchor_reference not in a family session;
// INVALID_ARGUMENT naming the field otherwise.
absl::Status CheckTrackingOnlyFields(const v1::SessionConfig& config, TaskKind task);
// SessionConfig.imitation_kernels into `reward` (a 0 field keeps its default); INVALID_ARGUMENT
// naming imitation_kernels.<term> outside (0, 10000], or imitation_kernels for a goal task.
absl::Status ApplyImitationKernels(const v1::SessionConfig& config, TaskKind task, ImitationRewardConfig* reward);
// The bodies of the named parts of `layout`, sorted (empty for none: every body); INVALID_ARGUMENT
// naming reward_parts[i] for an unknown or repeated part, or reward_parts for a goal task.
absl::StatusOr<std::vector<int>> ToRewardBodies(const google::protobuf::RepeatedPtrField<std::string>& reward_parts,
                                                const PartLayout& layout, TaskKind task);
// residual_scale must be 0 outside RESIDUAL; 0 in RESIDUAL means the default scale.
absl::StatusOr<ActionMapping> ToActionMapping(v1::ActionMode mode, float residual_scale);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SESSION_CONFIG_VALIDATION_H_
