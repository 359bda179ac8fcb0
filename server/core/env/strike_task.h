// Strike (ModSkill Table 4; ASE's and PULSE's strike): knock over a standing pillar (a real
// MuJoCo body, PhysicsOptions::strike_target) placed at random in front of the humanoid, with the
// right hand, wrist or elbow only; any other body touching it fails the episode.
#ifndef MODSKILL_SERVER_CORE_ENV_STRIKE_TASK_H_
#define MODSKILL_SERVER_CORE_ENV_STRIKE_TASK_H_

#include "server/core/env/goal_task.h"

namespace modskill {

class StrikeTask : public GoalTask {
 public:
  // Where a new target stands: this far in front of the root (m), within this angle of the
  // heading (rad), turned about the vertical at random.
  static constexpr double kMinDistance = 1.0, kMaxDistance = 3.0, kMaxBearing = M_PI / 2;
  // A target farther than this from the root has tunnelled or flown off: the episode fails.
  static constexpr double kLostDistance = 20.0;

  explicit StrikeTask(const GoalTaskContext* context) : GoalTask(context) {}

  // Stands the target up at a random place in front, at rest.
  void Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) override;
  // ASE's strike reward, which PULSE's and ModSkill's strike inherit:
  //   strike   = kTipWeight (1 - up . u_target), u_target the target's long axis (0 standing, 1 lying);
  //   approach = kApproachWeight exp(-4 max(0, 1 m/s - v_toward)^2) while the root moves toward the
  //              target (0 moving away), kApproachWeight once within kNearDistance or once it is down.
  // Tipping alone is a reward a head over walking skills never finds (it scored 0 in every run);
  // the approach term leads it to the target.
  void Reward(const HumanoidState& sim, const mjData* data, float* terms) override;
  static constexpr double kTipWeight = 0.6, kApproachWeight = 0.4;
  static constexpr double kApproachSpeed = 1.0;  // m/s
  static constexpr double kNearDistance = 1.0;   // m, root to target, horizontal: within striking reach
  // A body other than R_Hand, R_Wrist, R_Elbow touches the target, or the target is lost.
  bool Failed(const mjData* data) const override;
  // The target's position relative to the root (3), rotation (6, tangent-normal), linear and
  // angular velocity (3 + 3), in the heading frame.
  void WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const override;
  // From the root to the point kHandOffset to the left of the standing target (seen from the
  // root): a character walking there meets the target with its right hand, not its chest (a base
  // motion steered at the target itself ended 51 of 64 episodes on a forbidden touch). Once the
  // target is down (its axis more than 60 degrees off vertical), square to its left, so that the
  // character walks past it rather than over it (0.107 -> 0.151 for the prior alone).
  Vec3 GoalBearing(const HumanoidState& sim, const mjData* data) const override;
  static constexpr double kHandOffset = 0.45;  // m: the right hand's ~0.2 m, the target's 0.2 m half width

 protected:
  void DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) override;
  bool redraws_goals() const override { return false; }

 private:
  Vec3 position_ = Vec3::Zero();  // where the next target stands (world; z = half its height)
  double yaw_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_STRIKE_TASK_H_
