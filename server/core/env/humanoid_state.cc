#include "server/core/env/humanoid_state.h"

#include <algorithm>
#include <cmath>

#include "server/core/sim/body_kinematics.h"

namespace modskill {

void HumanoidState::Resize(int num_bodies, int num_hinges) {
  body_pos.resize(num_bodies);
  body_rot.resize(num_bodies);
  body_vel.resize(num_bodies);
  body_ang_vel.resize(num_bodies);
  dof_pos.resize(num_hinges);
  dof_vel.resize(num_hinges);
}

void ReadSimulatedState(const HumanoidModel& humanoid, const mjData* data, HumanoidState* state) {
  RootState root;
  if (humanoid.options().fixed_root) {
    root.pos = Vec3(0, 0, humanoid.options().fixed_root_height);
  } else {
    const mjtNum* q = data->qpos;
    root.pos = Vec3(q[0], q[1], q[2]);
    root.rot = Quat(q[3], q[4], q[5], q[6]).normalized();
    root.vel = Vec3(data->qvel[0], data->qvel[1], data->qvel[2]);
    // MuJoCo's free joint keeps its angular velocity in the body frame.
    root.ang_vel = root.rot * Vec3(data->qvel[3], data->qvel[4], data->qvel[5]);
  }
  const int qpos0 = humanoid.hinge_qpos_start(), qvel0 = humanoid.hinge_qvel_start();
  std::copy_n(data->qpos + qpos0, humanoid.num_hinges(), state->dof_pos.begin());
  std::copy_n(data->qvel + qvel0, humanoid.num_hinges(), state->dof_vel.begin());
  ComputeBodyKinematics(humanoid.spec(), root, state->dof_pos.data(), state->dof_vel.data(), state->body_pos.data(),
                        state->body_rot.data(), state->body_vel.data(), state->body_ang_vel.data());
}

void ReadReferenceState(const MotionClip& clip, int frame, HumanoidState* state) {
  const int bodies = clip.num_bodies, hinges = clip.num_hinges();
  std::copy_n(clip.body_pos.begin() + frame * bodies, bodies, state->body_pos.begin());
  std::copy_n(clip.body_rot.begin() + frame * bodies, bodies, state->body_rot.begin());
  std::copy_n(clip.body_vel.begin() + frame * bodies, bodies, state->body_vel.begin());
  std::copy_n(clip.body_ang_vel.begin() + frame * bodies, bodies, state->body_ang_vel.begin());
  std::copy_n(clip.dof_pos.begin() + frame * hinges, hinges, state->dof_pos.begin());
  std::copy_n(clip.dof_vel.begin() + frame * hinges, hinges, state->dof_vel.begin());
}

void ReadReferenceStateAt(const MotionClip& clip, double phase, HumanoidState* state) {
  const int last = clip.num_frames - 1;
  phase = std::clamp(phase, 0.0, static_cast<double>(last));
  const int f0 = static_cast<int>(std::floor(phase));
  const double w = phase - f0;
  ReadReferenceState(clip, f0, state);
  if (w == 0 || f0 >= last) return;
  const int bodies = clip.num_bodies, hinges = clip.num_hinges();
  const size_t b1 = static_cast<size_t>(f0 + 1) * bodies, h1 = static_cast<size_t>(f0 + 1) * hinges;
  for (int b = 0; b < bodies; ++b) {
    state->body_pos[b] += w * (clip.body_pos[b1 + b] - state->body_pos[b]);
    state->body_rot[b] = state->body_rot[b].slerp(w, clip.body_rot[b1 + b]);
    state->body_vel[b] += w * (clip.body_vel[b1 + b] - state->body_vel[b]);
    state->body_ang_vel[b] += w * (clip.body_ang_vel[b1 + b] - state->body_ang_vel[b]);
  }
  for (int h = 0; h < hinges; ++h) {
    state->dof_pos[h] += w * (clip.dof_pos[h1 + h] - state->dof_pos[h]);
    state->dof_vel[h] += w * (clip.dof_vel[h1 + h] - state->dof_vel[h]);
  }
}

void SetSimulationToReference(const HumanoidModel& humanoid, const MotionClip& clip, int frame, mjData* data) {
  const mjModel* m = humanoid.model();
  // A targeted reset instead of mj_resetData, which clears the whole arena: everything the
  // next mj_step reads besides qpos/qvel is zeroed here.
  mju_copy(data->qpos, m->qpos0, m->nq);
  mju_zero(data->qvel, m->nv);
  mju_zero(data->qacc_warmstart, m->nv);
  mju_zero(data->qfrc_applied, m->nv);
  mju_zero(data->xfrc_applied, 6 * m->nbody);
  if (m->nu > 0) mju_zero(data->ctrl, m->nu);
  if (m->na > 0) mju_zero(data->act, m->na);
  data->time = 0;
  for (int w = 0; w < mjNWARNING; ++w) data->warning[w] = mjWarningStat{0, 0};
  const int bodies = clip.num_bodies, hinges = clip.num_hinges();
  if (!humanoid.options().fixed_root) {
    const Vec3& pos = clip.body_pos[frame * bodies];
    const Quat& rot = clip.body_rot[frame * bodies];
    const Vec3& vel = clip.body_vel[frame * bodies];
    // MuJoCo's free joint takes its angular velocity in the body frame.
    const Vec3 ang_vel_local = rot.conjugate() * clip.body_ang_vel[frame * bodies];
    for (int k = 0; k < 3; ++k) data->qpos[k] = pos[k];
    data->qpos[3] = rot.w();
    data->qpos[4] = rot.x();
    data->qpos[5] = rot.y();
    data->qpos[6] = rot.z();
    for (int k = 0; k < 3; ++k) {
      data->qvel[k] = vel[k];
      data->qvel[3 + k] = ang_vel_local[k];
    }
  }
  const int qpos0 = humanoid.hinge_qpos_start(), qvel0 = humanoid.hinge_qvel_start();
  for (int h = 0; h < hinges; ++h) {
    data->qpos[qpos0 + h] = clip.dof_pos[frame * hinges + h];
    data->qvel[qvel0 + h] = clip.dof_vel[frame * hinges + h];
  }
}

}  // namespace modskill
