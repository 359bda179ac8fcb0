#include "server/core/env/base_motion_anchor.h"

#include "server/core/sim/rotation_math.h"

namespace modskill {

void AnchorToCharacter(const HumanoidState& anchor, const HumanoidState& sim, HumanoidState* target) {
  const Quat yaw = HeadingRotation(sim.body_rot[0]) * InverseHeadingRotation(anchor.body_rot[0]);
  const Vec3 from(anchor.body_pos[0].x(), anchor.body_pos[0].y(), 0.0);
  const Vec3 to(sim.body_pos[0].x(), sim.body_pos[0].y(), 0.0);
  const size_t bodies = target->body_pos.size();
  for (size_t b = 0; b < bodies; ++b) {
    target->body_pos[b] = yaw * (target->body_pos[b] - from) + to;
    target->body_rot[b] = yaw * target->body_rot[b];
    target->body_vel[b] = yaw * target->body_vel[b];
    target->body_ang_vel[b] = yaw * target->body_ang_vel[b];
  }
}

}  // namespace modskill
