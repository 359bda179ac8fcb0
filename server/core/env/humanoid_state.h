// The kinematic state of the humanoid in world coordinates, the common currency of the
// simulated body and the reference motion: observations and rewards compare two of these.
#ifndef MODSKILL_SERVER_CORE_ENV_HUMANOID_STATE_H_
#define MODSKILL_SERVER_CORE_ENV_HUMANOID_STATE_H_

#include <vector>

#include <mujoco/mujoco.h>

#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

struct HumanoidState {
  std::vector<Vec3> body_pos;
  std::vector<Quat> body_rot;
  std::vector<Vec3> body_vel;
  std::vector<Vec3> body_ang_vel;  // world frame
  std::vector<double> dof_pos;     // hinge angles, MuJoCo order
  std::vector<double> dof_vel;

  // Sizes every array once, so that the Read* functions never allocate.
  void Resize(int num_bodies, int num_hinges);
};

// From mjData's qpos and qvel alone (our own forward kinematics: no mj_kinematics needed).
void ReadSimulatedState(const HumanoidModel& humanoid, const mjData* data, HumanoidState* state);
void ReadReferenceState(const MotionClip& clip, int frame, HumanoidState* state);
// The reference at a fractional frame (a time-warped phase, clamped to the clip): positions,
// velocities and hinge angles interpolated linearly, rotations spherically. A whole `phase`
// reads exactly that frame.
void ReadReferenceStateAt(const MotionClip& clip, double phase, HumanoidState* state);

// Sets qpos/qvel to the reference frame (root pose, hinge angles and all velocities) and clears
// controls, applied forces and warnings; the next mj_step computes everything else.
void SetSimulationToReference(const HumanoidModel& humanoid, const MotionClip& clip, int frame, mjData* data);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_HUMANOID_STATE_H_
