// Forward kinematics of the humanoid from the root state and hinge angles and rates: body
// poses and velocities exactly as MuJoCo computes them for this tree (joints at body origins,
// hinges x-y-z), without touching mjData. Used for reference clips and for the simulated
// state in the step loop, where it replaces mj_kinematics/mj_comPos/mj_comVel.
#ifndef MODSKILL_SERVER_CORE_SIM_BODY_KINEMATICS_H_
#define MODSKILL_SERVER_CORE_SIM_BODY_KINEMATICS_H_

#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct RootState {
  Vec3 pos = Vec3::Zero();
  Quat rot = Quat::Identity();
  Vec3 vel = Vec3::Zero();      // world frame
  Vec3 ang_vel = Vec3::Zero();  // world frame
};

// Writes num_bodies entries to each output; dof arrays hold 3 per non-root body. Allocation free.
void ComputeBodyKinematics(const HumanoidSpec& spec, const RootState& root, const double* dof_pos,
                           const double* dof_vel, Vec3* body_pos, Quat* body_rot, Vec3* body_vel,
                           Vec3* body_ang_vel);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_BODY_KINEMATICS_H_
