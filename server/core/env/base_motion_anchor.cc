#include "server/core/env/base_motion_anchor.h"

#include <algorithm>
#include <cmath>

#include "server/core/sim/rotation_math.h"

namespace modskill {

PlanarMotion PlanarMotion::Between(const Vec3& from_pos, const Quat& from_rot, const Vec3& to_pos,
                                   const Quat& to_rot) {
  PlanarMotion motion;
  motion.yaw = HeadingRotation(to_rot) * InverseHeadingRotation(from_rot);
  motion.shift = Vec3(to_pos.x(), to_pos.y(), 0.0) - motion.yaw * Vec3(from_pos.x(), from_pos.y(), 0.0);
  return motion;
}

PlanarMotion PlanarMotion::After(const PlanarMotion& first) const {
  PlanarMotion both;
  both.yaw = yaw * first.yaw;
  both.shift = yaw * first.shift + shift;
  return both;
}

void PlanarMotion::Apply(HumanoidState* state) const {
  const size_t bodies = state->body_pos.size();
  for (size_t b = 0; b < bodies; ++b) {
    state->body_pos[b] = yaw * state->body_pos[b] + shift;
    state->body_rot[b] = yaw * state->body_rot[b];
    state->body_vel[b] = yaw * state->body_vel[b];
    state->body_ang_vel[b] = yaw * state->body_ang_vel[b];
  }
}

PlanarMotion AnchorToCharacter(const HumanoidState& anchor, const HumanoidState& sim, HumanoidState* target) {
  return AnchorToHeading(anchor, sim, HeadingAngle(sim.body_rot[0]), target);
}

double SteerHeading(double heading, const HumanoidState& sim, const Vec3& toward, double max_turn) {
  if (std::hypot(toward.x(), toward.y()) >= kSteeringDeadZone) {
    const double bearing = WrapAngle(std::atan2(toward.y(), toward.x()) - heading);
    heading += std::clamp(bearing, -max_turn, max_turn);
  }
  const double character = HeadingAngle(sim.body_rot[0]);
  return WrapAngle(character + std::clamp(WrapAngle(heading - character), -kMaxSteeringLead, kMaxSteeringLead));
}

PlanarMotion AnchorToHeading(const HumanoidState& anchor, const HumanoidState& sim, double heading,
                             HumanoidState* target) {
  const PlanarMotion motion = PlanarMotion::Between(anchor.body_pos[0], anchor.body_rot[0], sim.body_pos[0],
                                                    Quat(Eigen::AngleAxisd(heading, Vec3::UnitZ())));
  motion.Apply(target);
  return motion;
}

PlanarMotion ClipCycleMotion(const MotionClip& clip) {
  const int last = clip.num_frames - 1;
  return PlanarMotion::Between(clip.root_pos[0], clip.local(0, 0), clip.root_pos[last], clip.local(last, 0));
}

}  // namespace modskill
