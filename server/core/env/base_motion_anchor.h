// The base motion of a goal task (steer, reach, strike), observed as a tracker observes its
// reference. In a goal task the clip loops underneath as the base pose of residual actions, but
// the character walks wherever its goal takes it, so the clip's own world placement soon means
// nothing. Each step the next reference frame is carried by the horizontal rigid motion (a yaw
// and an xy shift) that puts the current reference frame's root on the character's root, facing
// the character's heading: the features then say "go on with the clip from where you are", which
// is what a tracker saw whenever it tracked well, and a frozen tracker's skill attention can read
// them (ModSkill's skills reused as a prior, learner/README.md).
#ifndef MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_
#define MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_

#include <cmath>

#include "server/core/env/humanoid_state.h"

namespace modskill {

// A yaw rotation about the vertical and a horizontal shift: p -> yaw * p + shift.
struct PlanarMotion {
  Quat yaw = Quat::Identity();
  Vec3 shift = Vec3::Zero();  // z = 0

  // The motion that puts root (from_pos, from_rot) on root (to_pos, to_rot) in x, y and heading.
  static PlanarMotion Between(const Vec3& from_pos, const Quat& from_rot, const Vec3& to_pos, const Quat& to_rot);
  // This motion after `first`: p -> this(first(p)).
  PlanarMotion After(const PlanarMotion& first) const;
  // Moves every body's position, rotation, velocity and angular velocity of `state`.
  void Apply(HumanoidState* state) const;
};

// Moves `target` by the planar motion that maps `anchor`'s root onto `sim`'s root (x, y and
// heading; heights and tilts are left as the clip has them), and returns that motion.
PlanarMotion AnchorToCharacter(const HumanoidState& anchor, const HumanoidState& sim, HumanoidState* target);

// A steered base motion (TaskSettings::steering_rate) keeps a heading of its own: each step it
// turns toward the goal's bearing (`toward`, world, horizontal part) by at most max_turn rad, and
// stays within kMaxSteeringLead of the character's heading, so that the character sees a heading
// error it must win back (a tracker corrects those) and the base motion never runs away from it.
// A goal closer than kSteeringDeadZone horizontally turns nothing: its bearing is noise.
inline constexpr double kSteeringDeadZone = 0.2;      // m
inline constexpr double kMaxSteeringLead = M_PI / 6;  // rad: within what a tracker wins back before 0.25 m
double SteerHeading(double heading, const HumanoidState& sim, const Vec3& toward, double max_turn);
// As AnchorToCharacter, but the anchor's root takes `heading` instead of the character's.
PlanarMotion AnchorToHeading(const HumanoidState& anchor, const HumanoidState& sim, double heading,
                             HumanoidState* target);

// A looping clip's displacement per cycle: the planar motion from its first frame's root to its
// last frame's (SessionConfig.loop_clips).
PlanarMotion ClipCycleMotion(const MotionClip& clip);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_
