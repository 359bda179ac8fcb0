#include "server/core/env/goal_task.h"

#include <algorithm>
#include <cmath>

#include "server/core/env/reach_task.h"
#include "server/core/env/steer_task.h"
#include "server/core/env/strike_task.h"

namespace modskill {

void GoalTask::StartGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  DrawGoal(sim, rng);
  const TaskSettings& settings = context_->settings;
  const double seconds =
      std::uniform_real_distribution<double>(settings.min_goal_interval_s, settings.max_goal_interval_s)(rng);
  steps_left_ = std::max(1, static_cast<int>(std::lround(seconds / context_->control_dt)));
}

void GoalTask::NextGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  if (redraws_goals() && --steps_left_ <= 0) StartGoal(sim, rng);
}

std::unique_ptr<GoalTask> MakeGoalTask(TaskKind kind, const GoalTaskContext* context) {
  switch (kind) {
    case TaskKind::kSteer:
      return std::make_unique<SteerTask>(context);
    case TaskKind::kReach:
      return std::make_unique<ReachTask>(context);
    case TaskKind::kStrike:
      return std::make_unique<StrikeTask>(context);
    case TaskKind::kTracking:
    case TaskKind::kVrTracking:
      return nullptr;
  }
  return nullptr;
}

}  // namespace modskill
