#include "server/service/session_config_validation.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/wire/policy_enums.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/family_episode.h"
#include "server/core/env/task_catalog.h"

namespace modskill {

absl::StatusOr<PartLayout> FindLayout(const PartLayoutCatalog& layouts, const std::string& name) {
  auto layout = layouts.Get(name.empty() ? layouts.default_name() : name);
  if (!layout.ok()) return absl::NotFoundError(layout.status().message());
  return layout;
}

absl::StatusOr<TerminationMode> ToTermination(v1::TerminationMode mode, v1::TerminationMode default_mode) {
  if (mode == v1::TERMINATION_UNSPECIFIED) mode = default_mode;
  switch (mode) {
    case v1::TRAINING:
      return TerminationMode::kTraining;
    case v1::EVALUATION:
      return TerminationMode::kEvaluation;
    case v1::NONE:
      return TerminationMode::kNone;
    default:
      return absl::InvalidArgumentError(absl::StrCat("termination: unknown value ", static_cast<int>(mode)));
  }
}

absl::StatusOr<double> ToTerminationDistance(float distance, TerminationMode mode) {
  if (distance == 0) return mode == TerminationMode::kEvaluation ? 0.5 : 0.25;  // the mode's default
  if (absl::Status status = ValidateTerminationDistance(distance); !status.ok()) return status;
  return distance;
}

absl::StatusOr<ActionMapping> ToActionMapping(v1::ActionMode mode, float residual_scale) {
  ActionMapping mapping;
  absl::StatusOr<ActionMode> parsed = ActionModeFromWire(mode);
  if (!parsed.ok()) return parsed.status();
  mapping.mode = *parsed;
  if (mapping.mode == ActionMode::kAbsolute) {
    if (residual_scale != 0) return absl::InvalidArgumentError("residual_scale: set, but action_mode is not RESIDUAL");
    return mapping;
  }
  if (residual_scale != 0) mapping.residual_scale = residual_scale;  // 0: the default
  if (absl::Status status = mapping.Validate(); !status.ok()) return status;
  return mapping;
}

absl::StatusOr<TaskSettings> ToTaskSettings(const v1::TaskSettings& wire) {
  TaskSettings settings;
  if (wire.min_speed() != 0) settings.min_speed = wire.min_speed();
  if (wire.max_speed() != 0) settings.max_speed = wire.max_speed();
  if (wire.min_goal_interval_s() != 0) settings.min_goal_interval_s = wire.min_goal_interval_s();
  if (wire.max_goal_interval_s() != 0) settings.max_goal_interval_s = wire.max_goal_interval_s();
  if (wire.has_reach_box_size()) settings.reach_box_size = wire.reach_box_size();
  if (wire.has_reach_center_x()) settings.reach_center[0] = wire.reach_center_x();
  if (wire.has_reach_center_y()) settings.reach_center[1] = wire.reach_center_y();
  if (wire.has_reach_center_z()) settings.reach_center[2] = wire.reach_center_z();
  if (wire.has_steering_rate()) settings.steering_rate = wire.steering_rate();
  if (absl::Status status = settings.Validate(); !status.ok()) return status;
  return settings;
}

absl::StatusOr<double> ToEnergyCoefficient(const v1::SessionConfig& config, bool family) {
  const double paper = ImitationRewardConfig().energy_coefficient;
  if (!config.has_energy_weight()) return paper;
  const float weight = config.energy_weight();
  if (!(std::isfinite(weight) && weight >= 0 && weight <= 100)) {
    return absl::InvalidArgumentError(absl::StrCat("energy_weight: ", weight, " must be finite, in [0, 100]"));
  }
  if (family && weight != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("energy_weight: ", weight, " set, but a family session has no energy penalty (0 or unset)"));
  }
  return paper * weight;
}

absl::Status CheckTrackingOnlyFields(const v1::SessionConfig& config, TaskKind task) {
  if (config.loop_clips() && task != TaskKind::kTracking) {
    return absl::InvalidArgumentError(absl::StrCat("loop_clips: tracking only; task ", TaskInfoOf(task).name,
                                                   " has its own episode ends"));
  }
  if (config.anchor_reference() && task != TaskKind::kTracking) {
    return absl::InvalidArgumentError(absl::StrCat("anchor_reference: tracking only; task ", TaskInfoOf(task).name,
                                                   " does not track a reference"));
  }
  if (config.anchor_position_only() && !config.anchor_reference()) {
    return absl::InvalidArgumentError("anchor_position_only: set, but anchor_reference is not");
  }
  if (config.anchor_reference() && config.family().params_size() > 0) {
    return absl::InvalidArgumentError("anchor_reference: not for a family session (its clip is tracked where it is)");
  }
  return absl::OkStatus();
}

absl::Status ApplyImitationKernels(const v1::SessionConfig& config, TaskKind task, ImitationRewardConfig* reward) {
  if (!config.has_imitation_kernels()) return absl::OkStatus();
  if (IsGoalTask(task)) {
    return absl::InvalidArgumentError(
        absl::StrCat("imitation_kernels: task ", TaskInfoOf(task).name, " has no imitation reward"));
  }
  const v1::ImitationKernels& wire = config.imitation_kernels();
  const std::pair<const char*, std::pair<float, double*>> kernels[] = {
      {"pos", {wire.pos(), &reward->k_pos}},
      {"rot", {wire.rot(), &reward->k_rot}},
      {"vel", {wire.vel(), &reward->k_vel}},
      {"ang_vel", {wire.ang_vel(), &reward->k_ang_vel}}};
  for (const auto& [name, value_and_target] : kernels) {
    const float k = value_and_target.first;
    if (k == 0) continue;  // the default
    if (!(std::isfinite(k) && k > 0 && k <= 10000)) {
      return absl::InvalidArgumentError(
          absl::StrCat("imitation_kernels.", name, ": ", k, " must be finite, in (0, 10000] (0: the default)"));
    }
    *value_and_target.second = k;
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<ParamRange>> ToFamilyRanges(const v1::SessionConfig& config, ActionMode action_mode,
                                                       TaskKind task) {
  std::vector<ParamRange> ranges;
  if (!config.has_family() || config.family().params_size() == 0) return ranges;
  for (const v1::FamilyParameterRange& wire : config.family().params()) {
    ranges.push_back(ParamRange{wire.name(), wire.lo(), wire.hi()});
  }
  if (absl::Status status = ValidateFamilySession(ranges, "family.params", config.motions_size(), task, action_mode,
                                                  config.loop_clips());
      !status.ok()) {
    return status;
  }
  return ranges;
}

absl::StatusOr<std::vector<int>> ToRewardBodies(const google::protobuf::RepeatedPtrField<std::string>& reward_parts,
                                                const PartLayout& layout, TaskKind task) {
  if (reward_parts.empty()) return std::vector<int>();
  if (IsGoalTask(task)) {
    return absl::InvalidArgumentError(
        absl::StrCat("reward_parts: task ", TaskInfoOf(task).name, " has no imitation reward to restrict"));
  }
  auto bodies = layout.BodiesOfParts({reward_parts.begin(), reward_parts.end()}, "reward_parts");
  if (!bodies.ok()) return bodies.status();
  std::sort(bodies->begin(), bodies->end());  // ImitationRewardConfig::bodies is sorted
  return bodies;
}

absl::StatusOr<SessionSettings> ParseSessionConfig(const v1::SessionConfig& config, int max_envs_per_session,
                                                   int max_library_clips, const PartLayoutCatalog& layouts) {
  SessionSettings settings;
  if (config.num_envs() < 1) {
    return absl::InvalidArgumentError(absl::StrCat("num_envs: ", config.num_envs(), " must be >= 1"));
  }
  if (config.num_envs() > max_envs_per_session) {
    return absl::ResourceExhaustedError(absl::StrCat("num_envs: ", config.num_envs(),
                                                     " exceeds --max_envs_per_session=", max_envs_per_session));
  }
  if (config.max_episode_steps() < 0) return absl::InvalidArgumentError("max_episode_steps: must be >= 0");
  auto layout = FindLayout(layouts, config.part_layout());
  if (!layout.ok()) return layout.status();
  auto termination = ToTermination(config.termination(), v1::TRAINING);
  if (!termination.ok()) return termination.status();
  auto distance = ToTerminationDistance(config.termination_distance(), *termination);
  if (!distance.ok()) return distance.status();
  const bool family = config.has_family() && config.family().params_size() > 0;
  // A family's action is a displacement of its reference: residual, whether asked or left unset.
  const v1::ActionMode action_mode =
      family && config.action_mode() == v1::ACTION_MODE_UNSPECIFIED ? v1::RESIDUAL : config.action_mode();
  auto action_mapping = ToActionMapping(action_mode, config.residual_scale());
  if (!action_mapping.ok()) return action_mapping.status();
  auto termination_bodies = TerminationBodiesFromWire(config.termination_bodies());
  if (!termination_bodies.ok()) return termination_bodies.status();
  if (!v1::AmpObs_IsValid(config.amp_obs())) return absl::InvalidArgumentError("amp_obs: unknown value");
  auto task = ParseTask(config.task());
  if (!task.ok()) return task.status();
  auto task_settings = ToTaskSettings(config.task_settings());
  if (!task_settings.ok()) return task_settings.status();
  if (absl::Status status = CheckTrackingOnlyFields(config, *task); !status.ok()) return status;
  auto family_ranges = ToFamilyRanges(config, action_mapping->mode, *task);
  if (!family_ranges.ok()) return family_ranges.status();
  auto reward_bodies = ToRewardBodies(config.reward_parts(), *layout, *task);
  if (!reward_bodies.ok()) return reward_bodies.status();
  auto energy_coefficient = ToEnergyCoefficient(config, family);
  if (!energy_coefficient.ok()) return energy_coefficient.status();
  if (config.reward_relative_to_root() && IsGoalTask(*task)) {
    return absl::InvalidArgumentError(absl::StrCat("reward_relative_to_root: task ", TaskInfoOf(*task).name,
                                                   " has no imitation reward"));
  }
  if (absl::Status status = ApplyImitationKernels(config, *task, &settings.env.reward); !status.ok()) return status;
  settings.amp_frames = config.amp_obs() == v1::NEWEST ? 1 : config.amp_obs() == v1::OMIT ? 0 : kAmpHistory;
  if (config.motions_size() > max_library_clips) {
    return absl::InvalidArgumentError(absl::StrCat("motions: ", config.motions_size(),
                                                   " names, more than the library may hold (", max_library_clips,
                                                   ", --max_library_clips)"));
  }

  settings.num_envs = config.num_envs();
  settings.seed = config.seed();
  settings.layout = *std::move(layout);
  settings.env.termination = *termination;
  settings.env.termination_distance = *distance;
  settings.env.termination_bodies = *termination_bodies;
  settings.env.action = *action_mapping;
  settings.env.max_episode_steps = config.max_episode_steps();
  settings.env.task = *task;
  settings.env.task_settings = *task_settings;
  settings.env.loop_clips = config.loop_clips();
  settings.env.anchor_reference = config.anchor_reference();
  settings.env.anchor_position_only = config.anchor_position_only();
  settings.env.reference_frames = config.reference_frames() == 0 ? 1 : config.reference_frames();  // 0: one
  settings.env.family = *std::move(family_ranges);
  settings.env.reward.bodies = *std::move(reward_bodies);
  settings.env.reward.relative_to_root = config.reward_relative_to_root();
  settings.env.reward.energy_coefficient = *energy_coefficient;
  if (absl::Status status = CheckReferenceFrames(settings.env); !status.ok()) return status;
  // A family leaves its clip by design (a higher jump, another gravity): a loose default.
  if (family && config.termination_distance() == 0 && *termination == TerminationMode::kTraining) {
    settings.env.termination_distance = kFamilyDefaultTerminationDistance;
  }
  return settings;
}

}  // namespace modskill
