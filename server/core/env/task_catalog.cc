#include "server/core/env/task_catalog.h"

#include <cmath>
#include <iterator>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

const std::vector<TaskInfo>& AllTasks() {
  static const std::vector<TaskInfo>* const kTasks = new std::vector<TaskInfo>{
      {TaskKind::kTracking, "tracking", 0, {"pos", "rot", "vel", "ang_vel", "energy"},
       "imitate the clip; goal = every body's reference features (in the observation, body by body)"},
      {TaskKind::kSteer, "steer", 3, {"speed", "facing", "energy"},
       "goal = target direction (heading frame, x y) and speed (m/s); r = 0.7 exp(-0.25 ((v* - d.v)^2 + "
       "0.1 |v_tangential|^2)) + 0.3 max(0, facing.d)"},
      {TaskKind::kReach, "reach", 3, {"reach", "energy"},
       "goal = target point minus the root (heading frame, m), sampled in a 2 m box around (0, 0, 1) "
       "(task_settings.reach_box_size, reach_center_*); "
       "r = exp(-5 |p_R_Hand - c|^2)"},
      {TaskKind::kStrike, "strike", 15, {"strike", "approach", "energy"},
       "goal = the target pillar's position (relative to the root), rotation, linear and angular velocity "
       "(heading frame); r = 0.6 (1 - up.u_target) + 0.4 exp(-4 max(0, 1 - v_toward)^2) (1 within 1 m or "
       "once it is down; ASE's); fails when a body other than R_Hand, R_Wrist, R_Elbow touches it"},
      {TaskKind::kVrTracking, "vr_tracking", 24 * kNumVrBodies, {"pos", "rot", "vel", "ang_vel", "energy"},
       "goal = the reference head and hands only (position, rotation, velocity and angular velocity "
       "differences, reference pose; heading frame); imitation reward; success and errors over the "
       "three bodies",
       {std::begin(kVrBodies), std::end(kVrBodies)}},
  };
  return *kTasks;
}

const TaskInfo& TaskInfoOf(TaskKind kind) {
  for (const TaskInfo& task : AllTasks()) {
    if (task.kind == kind) return task;
  }
  return AllTasks().front();
}

std::vector<int> TrackedBodyIndices(TaskKind kind, const HumanoidSpec& spec) {
  std::vector<int> indices;
  for (const std::string& name : TaskInfoOf(kind).tracked_bodies) indices.push_back(spec.BodyIndex(name));
  return indices;
}

absl::StatusOr<TaskKind> ParseTask(absl::string_view name) {
  if (name.empty()) return TaskKind::kTracking;
  std::vector<std::string> names;
  for (const TaskInfo& task : AllTasks()) {
    if (name == task.name) return task.kind;
    names.push_back(task.name);
  }
  return absl::InvalidArgumentError(
      absl::StrCat("task: unknown task '", name, "' (known: ", absl::StrJoin(names, ", "), ")"));
}

absl::Status TaskSettings::Validate() const {
  if (!std::isfinite(min_speed) || min_speed < 0 || min_speed > 10) {
    return absl::InvalidArgumentError(absl::StrCat("task_settings.min_speed: ", min_speed, " outside [0, 10] m/s"));
  }
  if (!std::isfinite(max_speed) || max_speed < min_speed || max_speed > 10) {
    return absl::InvalidArgumentError(
        absl::StrCat("task_settings.max_speed: ", max_speed, " outside [min_speed = ", min_speed, ", 10] m/s"));
  }
  if (!std::isfinite(min_goal_interval_s) || min_goal_interval_s <= 0 || min_goal_interval_s > 3600) {
    return absl::InvalidArgumentError(
        absl::StrCat("task_settings.min_goal_interval_s: ", min_goal_interval_s, " outside (0, 3600] s"));
  }
  if (!std::isfinite(max_goal_interval_s) || max_goal_interval_s < min_goal_interval_s ||
      max_goal_interval_s > 3600) {
    return absl::InvalidArgumentError(absl::StrCat("task_settings.max_goal_interval_s: ", max_goal_interval_s,
                                                   " outside [min_goal_interval_s = ", min_goal_interval_s,
                                                   ", 3600] s"));
  }
  if (!std::isfinite(reach_box_size) || reach_box_size <= 0 || reach_box_size > 4) {
    return absl::InvalidArgumentError(
        absl::StrCat("task_settings.reach_box_size: ", reach_box_size, " outside (0, 4] m"));
  }
  const double half = 0.5 * reach_box_size;
  constexpr const char* kCenterFields[3] = {"reach_center_x", "reach_center_y", "reach_center_z"};
  for (int axis = 0; axis < 3; ++axis) {
    const double low = axis == 2 ? 0.0 : -3.0;
    const double c = reach_center[axis];
    if (!std::isfinite(c) || c - half < low || c + half > 3.0) {
      return absl::InvalidArgumentError(absl::StrCat("task_settings.", kCenterFields[axis], ": ", c,
                                                     " puts the reach box (edge ", reach_box_size,
                                                     " m) outside [", low, ", 3] m"));
    }
  }
  return absl::OkStatus();
}

}  // namespace modskill
