// Steer (ModSkill Table 4; the heading task of ASE and PULSE): move along a target direction at a
// target speed, facing where you go. Direction and speed change at random intervals.
#ifndef MODSKILL_SERVER_CORE_ENV_STEER_TASK_H_
#define MODSKILL_SERVER_CORE_ENV_STEER_TASK_H_

#include "server/core/env/goal_task.h"

namespace modskill {

class SteerTask : public GoalTask {
 public:
  explicit SteerTask(const GoalTaskContext* context) : GoalTask(context) {}

  void Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) override;
  // speed = 0.7 exp(-0.25 ((v* - d.v)^2 + 0.1 |v - (d.v) d|^2)), v the root's horizontal velocity
  // over the step; facing = 0.3 max(0, f.d), f the root's heading direction.
  void Reward(const HumanoidState& sim, const mjData* data, float* terms) override;
  // [d_x, d_y] in the heading frame, v* (m/s).
  void WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const override;
  // The target direction.
  Vec3 GoalBearing(const HumanoidState& sim, const mjData* data) const override { return direction_; }

  // The goal, for tests: the target direction (world, unit, horizontal) and speed.
  Vec3 direction() const { return direction_; }
  double speed() const { return speed_; }

 protected:
  void DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) override;

 private:
  Vec3 direction_ = Vec3::UnitX();
  double speed_ = 0;
  Vec3 previous_root_ = Vec3::Zero();
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_STEER_TASK_H_
