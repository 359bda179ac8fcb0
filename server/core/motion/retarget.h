// Retargeting of another skeleton's motion onto the 24-body humanoid by matching bone
// directions: each mapped body takes its source joint's world rotation, corrected by the
// rotation between the two skeletons' rest poses, so that bones point the same way.
#ifndef MODSKILL_SERVER_CORE_MOTION_RETARGET_H_
#define MODSKILL_SERVER_CORE_MOTION_RETARGET_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

// A source motion in its own frame and units.
struct RetargetSource {
  std::string what;  // file name for messages
  std::vector<std::string> joint_names;
  std::vector<int> parents;       // parents precede children
  std::vector<Vec3> rest_offsets;  // joint position in the parent frame at rest
  int num_frames = 0;
  double fps = 0;
  std::vector<Quat> local_rot;  // [frame * joints + joint]; joint 0: world rotation of the root
  std::vector<Vec3> root_pos;   // [frame]
  Mat3 to_world = Mat3::Identity();  // source frame -> simulation frame (z-up)
};

struct BodyMapping {
  enum class Kind {
    kMapped,        // takes `source`'s rotation
    kSpread,        // shares the rotation between its mapped ancestor and mapped descendant
    kFollowParent,  // keeps its rest pose relative to its parent
  };
  std::string target;
  Kind kind = Kind::kMapped;
  std::string source;            // kMapped
  std::string source_direction;  // source joint that the bone points to at rest (optional)
  std::string target_direction;  // target body that the bone points to at rest (optional)
};

struct RetargetMap {
  std::vector<BodyMapping> bodies;  // target bodies not listed follow their parent
  // Source joints of the left and right leg (hip, knee, ankle) set the scale and the facing.
  std::string left_hip, left_knee, left_ankle, right_hip;
};

absl::StatusOr<MotionClip> RetargetToHumanoid(const RetargetSource& source, const RetargetMap& map,
                                              const HumanoidSpec& spec);

// y-up (x, y, z) -> z-up (z, x, y): SMPL, BVH and DeepMimic frames to the simulation frame.
Mat3 YupToZupMatrix();

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_RETARGET_H_
