// Sizes and slices of everything an env emits, derived once from the humanoid and the part
// layout. This is what Describe ships so that no client hard-codes a size.
#ifndef MODSKILL_SERVER_CORE_ENV_ENV_SPEC_H_
#define MODSKILL_SERVER_CORE_ENV_ENV_SPEC_H_

#include <string>
#include <vector>

#include "common/policy/family_parameters.h"
#include "common/policy/physics_settings.h"
#include "server/core/env/task_catalog.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/part_layout.h"

namespace modskill {

struct Slice {
  int start = 0;
  int size = 0;
};

// Observation per body (PHC, heading frame), bodies in part order:
//   self  = [local pos 3 (not for the root), rot 6, vel 3, angvel 3] (+ root height 1 for the root)
//   task  = [dpos 3, drot 6, dvel 3, dangvel 3, ref local pos 3, ref local rot 6]
// so a body contributes [self | task]: 15 + 24, the root 13 + 24. Total 358 + 576 = 934.
// The goal tasks (steer, reach, strike) write the same 934 (their reference: the base motion
// anchored to the character, base_motion_anchor.h) and then the goal: [934 | goal]. VR tracking
// writes the self features only, body by body in the same order, then its goal: [358 | 72].
// A tracker that observes N upcoming reference frames (EnvSpec::reference_frames) has N task
// blocks per body, the next frame's first: [self | task(t+1) | ... | task(t+N)].
inline constexpr int kSelfFeaturesPerBody = 15;
inline constexpr int kSelfFeaturesRoot = 13;
inline constexpr int kTaskFeaturesPerBody = 24;
// AMP features per frame: root height 1, root rot 6, root vel 3, root angvel 3, joint rotations
// 6 per non-root body, hinge velocities, key body positions 3 each. 232 for 24 bodies.
inline constexpr int kAmpHistory = 10;
inline const char* const kAmpKeyBodies[] = {"R_Ankle", "L_Ankle", "R_Wrist", "L_Wrist"};
inline constexpr int kNumAmpKeyBodies = 4;

// Tracking's reward terms, reported separately; reward = their sum. Task envs have their own
// (TaskInfo::reward_terms), energy always last.
enum RewardTerm { kRewardPos = 0, kRewardRot, kRewardVel, kRewardAngVel, kRewardEnergy, kNumRewardTerms };
const char* RewardTermName(int term);

struct EnvSpec {
  PartLayout layout;
  std::vector<int> body_order;     // spec body index at each observation position
  std::vector<int> body_obs_start;  // per spec body: where its block starts in obs
  std::vector<Slice> part_obs;      // per part
  std::vector<Slice> part_action;   // per part
  std::vector<int> action_hinge;    // per action index: hinge index (MuJoCo order)
  std::vector<int> amp_key_bodies;  // spec body indices
  TaskKind task = TaskKind::kTracking;
  Slice goal_obs;                         // task envs: the goal after every body's features
  std::vector<std::string> reward_terms;  // StepResult.reward_terms columns
  int obs_size = 0;
  int self_obs_size = 0;
  int task_obs_size = 0;  // the reference features (tracking, goal tasks) and the goal
  int action_size = 0;
  int reference_frames = 1;  // tracking: the task blocks per body (reference_frames.h)
  int amp_obs_per_frame = 0;
  int amp_obs_size = 0;  // kAmpHistory frames, newest first
  double control_dt = 0;
  PhysicsSettings physics;  // the humanoid's rate and servos, as policies record them
  std::vector<std::string> body_names;
  std::vector<std::string> joint_names;  // hinges in action order
  // A motor-skill family session (family_env.h): its parameter ranges, and the action index of
  // the time warp (the last action; -1 outside a family).
  std::vector<ParamRange> family;
  int time_warp_action = -1;
};

// reference_frames above 1: tracking only (the session's validation refuses it elsewhere).
EnvSpec MakeEnvSpec(const HumanoidModel& humanoid, const PartLayout& layout, TaskKind task = TaskKind::kTracking,
                    int reference_frames = 1);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_ENV_SPEC_H_
