#include "server/core/sim/body_kinematics.h"

namespace modskill {

void ComputeBodyKinematics(const HumanoidSpec& spec, const RootState& root, const double* dof_pos,
                           const double* dof_vel, Vec3* body_pos, Quat* body_rot, Vec3* body_vel,
                           Vec3* body_ang_vel) {
  body_pos[0] = root.pos;
  body_rot[0] = root.rot;
  body_vel[0] = root.vel;
  body_ang_vel[0] = root.ang_vel;
  for (int b = 1; b < spec.num_bodies(); ++b) {
    const int p = spec.body(b).parent;
    const double* angle = dof_pos + 3 * (b - 1);
    const double* rate = dof_vel + 3 * (b - 1);
    const Quat r0(Eigen::AngleAxisd(angle[0], HingeAxis(0)));
    const Quat r1(Eigen::AngleAxisd(angle[1], HingeAxis(1)));
    const Quat r2(Eigen::AngleAxisd(angle[2], HingeAxis(2)));
    const Vec3 offset = body_rot[p] * spec.body(b).offset;
    body_pos[b] = body_pos[p] + offset;
    body_rot[b] = body_rot[p] * (r0 * r1 * r2);
    // Each hinge's rate about its axis as moved by the hinges before it.
    const Vec3 relative = rate[0] * HingeAxis(0) + r0 * (rate[1] * HingeAxis(1) + r1 * (rate[2] * HingeAxis(2)));
    body_ang_vel[b] = body_ang_vel[p] + body_rot[p] * relative;
    body_vel[b] = body_vel[p] + body_ang_vel[p].cross(offset);
  }
}

}  // namespace modskill
