// Held reach poses: a base clip with one hand brought to a target point over kHoldRampSeconds
// and held there, the arm's pose found by inverse kinematics (reach_ik.h). A reach head can only
// steer its skills toward points where some skill holds the hand, and the arms of other motions
// seldom stop where a reach's targets are (issue 13).
#ifndef MODSKILL_SERVER_CORE_MOTION_REACH_POSE_H_
#define MODSKILL_SERVER_CORE_MOTION_REACH_POSE_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct ReachPoseRequest {
  std::string name;              // the new clip's name (ValidateClipName)
  std::string label;             // its caption; empty: "<base>, <hand> held at (x, y, z)"
  int hand = -1;                 // spec body whose position reaches the target
  std::vector<int> moved_bodies;  // non-root bodies whose hinges turn: the hand or its ancestors
  // The target in the reach task's frame (ReachTask): the heading frame of the root on its ground
  // point, z = height above the floor, at the frame where the ramp ends.
  Vec3 target = Vec3::Zero();
};

struct ReachPose {
  MotionClip clip;
  double distance = 0;  // hand to target once held (m): what the joint ranges leave of the reach
};

// Every body but the moved ones keeps the base's motion; each moved body turns from the base's
// rotation to the solved one along HoldRampWeight and keeps it. The result is placed on the
// ground and has its kinematics computed.
absl::StatusOr<ReachPose> MakeReachPose(const HumanoidSpec& spec, const MotionClip& base,
                                        const ReachPoseRequest& request);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_REACH_POSE_H_
