// The tasks a session may run (SessionConfig.task): tracking, and the downstream task envs that
// reuse learned skills (ModSkill section 3.5, docs/DESIGN.md "Downstream"). Each task's goal
// size, reward terms and settings live here, once; Describe lists them and the env spec is sized
// from them.
#ifndef MODSKILL_SERVER_CORE_ENV_TASK_CATALOG_H_
#define MODSKILL_SERVER_CORE_ENV_TASK_CATALOG_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/task_episode.h"
#include "common/task_settings.h"

namespace modskill {

class HumanoidSpec;

enum class TaskKind { kTracking, kSteer, kReach, kStrike, kVrTracking };

struct TaskInfo {
  TaskKind kind;
  const char* name;
  int goal_size;                          // goal features after the self features (0: tracking)
  std::vector<std::string> reward_terms;  // reward = their sum; "energy" always last
  const char* description;
  std::vector<std::string> tracked_bodies = {};  // vr_tracking: kVrBodies; the goal and termination watch them
};

// Every task, tracking first.
const std::vector<TaskInfo>& AllTasks();
const TaskInfo& TaskInfoOf(TaskKind kind);
// The task's tracked bodies as indices into `spec`'s bodies, in TaskInfo order; empty for a task
// that tracks no subset (every body counts).
std::vector<int> TrackedBodyIndices(TaskKind kind, const HumanoidSpec& spec);
// "" and "tracking" are tracking; INVALID_ARGUMENT naming the value and the known tasks otherwise.
absl::StatusOr<TaskKind> ParseTask(absl::string_view name);

// Steer, reach and strike pursue a goal of their own after the start state (GoalTask); tracking
// and VR tracking follow the clip.
inline bool IsGoalTask(TaskKind kind) {
  return kind == TaskKind::kSteer || kind == TaskKind::kReach || kind == TaskKind::kStrike;
}

// The goal features of the VR task, per watched body: the tracking task features of that body.
inline constexpr const char* kVrBodies[] = {"Head", "L_Hand", "R_Hand"};
inline constexpr int kNumVrBodies = 3;

// Steer's and reach's goals (SessionConfig.task_settings): TaskSettings (common/task_settings.h).

// Goal tasks' step limit: TaskEpisodeSteps (common/policy/task_episode.h); tracking and VR
// tracking run to the clip's end instead.

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_TASK_CATALOG_H_
