#include "server/core/env/env_spec.h"

namespace modskill {

const char* RewardTermName(int term) {
  static const char* const kNames[kNumRewardTerms] = {"pos", "rot", "vel", "ang_vel", "energy"};
  return term >= 0 && term < kNumRewardTerms ? kNames[term] : "unknown";
}

EnvSpec MakeEnvSpec(const HumanoidModel& humanoid, const PartLayout& layout, TaskKind task, int reference_frames) {
  const HumanoidSpec& spec = humanoid.spec();
  EnvSpec env;
  env.layout = layout;
  env.task = task;
  const TaskInfo& info = TaskInfoOf(task);
  env.reward_terms = info.reward_terms;
  // Tracking interleaves each body's reference features with its self features; so do the goal
  // tasks, whose reference is their base motion anchored to the character
  // (base_motion_anchor.h). VR tracking has only its three bodies' features, in the goal. Task
  // envs append the goal after every body's features.
  env.reference_frames = task == TaskKind::kTracking ? reference_frames : 1;
  const int per_body_task =
      task == TaskKind::kTracking || IsGoalTask(task) ? kTaskFeaturesPerBody * env.reference_frames : 0;
  env.body_order = layout.BodyOrder();
  env.body_obs_start.assign(spec.num_bodies(), 0);
  const std::vector<std::string> hinge_names = spec.HingeNames();
  int obs = 0, action = 0;
  for (const BodyPart& part : layout.parts) {
    Slice obs_slice{obs, 0}, action_slice{action, 0};
    for (int body : part.bodies) {
      env.body_obs_start[body] = obs;
      const int self = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
      obs += self + per_body_task;
      env.self_obs_size += self;
      env.task_obs_size += per_body_task;
      if (body != 0) {
        for (int a = 0; a < 3; ++a) {
          const int hinge = 3 * (body - 1) + a;
          env.action_hinge.push_back(hinge);
          env.joint_names.push_back(hinge_names[hinge]);
        }
        action += 3;
      }
    }
    obs_slice.size = obs - obs_slice.start;
    action_slice.size = action - action_slice.start;
    env.part_obs.push_back(obs_slice);
    env.part_action.push_back(action_slice);
  }
  env.goal_obs = Slice{obs, info.goal_size};
  obs += info.goal_size;
  env.task_obs_size += info.goal_size;
  env.obs_size = obs;
  env.action_size = action;
  for (const char* name : kAmpKeyBodies) env.amp_key_bodies.push_back(spec.BodyIndex(name));
  env.amp_obs_per_frame = 1 + 6 + 3 + 3 + 6 * (spec.num_bodies() - 1) + spec.num_hinges() + 3 * kNumAmpKeyBodies;
  env.amp_obs_size = kAmpHistory * env.amp_obs_per_frame;
  env.control_dt = humanoid.options().control_dt();
  const PhysicsOptions& physics = humanoid.options();
  env.physics.physics_dt = physics.physics_dt();
  env.physics.pd_mode = std::string(PdModeName(physics.pd_mode));
  env.physics.pd_gain_scale = physics.pd_gain_scale;
  env.physics.damp_to_reference_rate = physics.damp_to_reference_rate;
  env.body_names = spec.BodyNames();
  return env;
}

}  // namespace modskill
