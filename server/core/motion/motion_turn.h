// Turning a clip's path: the same steps along a path that bends at a constant yaw rate. A walk
// tracker trained on straight walks never sees a turn, yet steer and strike ask it to walk
// toward targets up to 90 degrees aside; bent copies of its clips put turning within its reach
// (the locomotion data PULSE and ASE train their skills on turns as much as it goes straight).
#ifndef MODSKILL_SERVER_CORE_MOTION_MOTION_TURN_H_
#define MODSKILL_SERVER_CORE_MOTION_MOTION_TURN_H_

#include <string>

#include "absl/status/statusor.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

// The largest |yaw rate| TurnClip accepts (rad/s): a half turn per second, past which the
// unchanged footsteps would slide across the floor more than they step.
inline constexpr double kMaxTurnRate = M_PI;

struct TurnRequest {
  std::string name;       // the new clip's name (ValidateClipName)
  double yaw_rate = 0.0;  // rad/s about the vertical, positive to the left (counter-clockwise)
  std::string label;      // the new clip's caption; empty: the base's with the rate
};

// Frame f's root heading turned by yaw_rate x f / fps, and each frame's horizontal root
// displacement turned by the same angle, so the path bends while every body's motion relative to
// the root stays the base's; heights are unchanged. The first frame is the base's. The result
// has its kinematics computed; INVALID_ARGUMENT when the name, the rate (finite, |rate| <=
// kMaxTurnRate) or the clip's skeleton do not fit.
absl::StatusOr<MotionClip> TurnClip(const HumanoidSpec& spec, const MotionClip& base, const TurnRequest& request);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_MOTION_TURN_H_
