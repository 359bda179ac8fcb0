// Reach (ModSkill Table 4): bring the right hand to a target point drawn in a 2 m box centred at
// (0, 0, 1) m in the heading frame (TaskSettings may move and shrink the box); a new point at
// random intervals.
#ifndef MODSKILL_SERVER_CORE_ENV_REACH_TASK_H_
#define MODSKILL_SERVER_CORE_ENV_REACH_TASK_H_

#include "server/core/env/goal_task.h"

namespace modskill {

class ReachTask : public GoalTask {
 public:
  explicit ReachTask(const GoalTaskContext* context) : GoalTask(context) {}

  void Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) override { StartGoal(sim, rng); }
  // reach = exp(-5 |p_R_Hand - c|^2)
  void Reward(const HumanoidState& sim, const mjData* data, float* terms) override;
  // c - p_root in the heading frame (m).
  void WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const override;
  // From the root to the target point.
  Vec3 GoalBearing(const HumanoidState& sim, const mjData* data) const override { return target_ - sim.body_pos[0]; }

  Vec3 target() const { return target_; }  // world (m), for tests

 protected:
  void DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) override;

 private:
  Vec3 target_ = Vec3::Zero();
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_REACH_TASK_H_
