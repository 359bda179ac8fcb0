// The goal of a task env that reuses skills without following a reference (steer, reach,
// strike): what it asks of the humanoid, how it rewards it, when it asks something new and when
// the episode fails for the task's own reasons. One per env; the env owns the physics, the fall
// check and the episode.
#ifndef MODSKILL_SERVER_CORE_ENV_GOAL_TASK_H_
#define MODSKILL_SERVER_CORE_ENV_GOAL_TASK_H_

#include <memory>
#include <random>
#include <vector>

#include <mujoco/mujoco.h>

#include "server/core/env/env_spec.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/env/task_catalog.h"
#include "server/core/sim/rotation_math.h"

namespace modskill {

// What every env of a batch shares.
struct GoalTaskContext {
  TaskSettings settings;
  double control_dt = 0;  // s per control step
  int right_hand = -1;    // spec body index of R_Hand (reach)
  // Strike: the target's qpos and qvel addresses, its geom, and which geoms may touch it (the
  // right hand, wrist and elbow, the floor); set when the model has a target.
  int target_qpos = -1, target_qvel = -1, target_geom = -1;
  std::vector<char> may_touch_target;  // per MuJoCo geom
};

class GoalTask {
 public:
  virtual ~GoalTask() = default;
  // A new episode starts in `sim` (`data` holds it): draw the first goal, place its objects.
  virtual void Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) = 0;
  // After each control step: the task's reward terms, energy excluded (weighted; their sum is at
  // most 1), written to terms[0 .. reward_terms - 2].
  virtual void Reward(const HumanoidState& sim, const mjData* data, float* terms) = 0;
  // Whether the step just taken fails the episode for the task's own reasons (a fall is the
  // env's to check).
  virtual bool Failed(const mjData* data) const { return false; }
  // After the reward: counts the goal's time down and draws a new goal when it is up.
  void NextGoal(const HumanoidState& sim, std::mt19937_64& rng);
  // goal_obs.size floats for the observation, in the heading frame of `sim`.
  virtual void WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const = 0;
  // Which way the goal lies from the character (world; only x and y count): the way a steered
  // base motion turns (TaskSettings::steering_rate).
  virtual Vec3 GoalBearing(const HumanoidState& sim, const mjData* data) const = 0;

 protected:
  explicit GoalTask(const GoalTaskContext* context) : context_(context) {}
  virtual void DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) = 0;
  // false: the goal holds for the whole episode (strike's target).
  virtual bool redraws_goals() const { return true; }
  // Draws the goal and how many steps it holds: U(min, max goal interval), at least 1.
  void StartGoal(const HumanoidState& sim, std::mt19937_64& rng);

  const GoalTaskContext* context_;
  int steps_left_ = 0;
};

// The goal task of `kind` (steer, reach or strike); nullptr for tracking and VR tracking.
std::unique_ptr<GoalTask> MakeGoalTask(TaskKind kind, const GoalTaskContext* context);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_GOAL_TASK_H_
