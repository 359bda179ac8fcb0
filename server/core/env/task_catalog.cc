#include "server/core/env/task_catalog.h"

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

}  // namespace modskill
