// Biovision Hierarchy (BVH) motion capture files: the skeleton (joint names, parents, offsets,
// channels) and, per frame, the root translation and every joint's local rotation.
//
// Conventions:
// - Rotation channels compose in the order they are listed: "Zrotation Yrotation Xrotation"
//   gives R = Rz * Ry * Rx (angles in degrees). The stored quaternion is that R.
// - Only the root's position channels are used. Position channels of other joints are read
//   (their values count toward the frame's width) but ignored: the skeleton keeps its OFFSETs.
// - Root translation per axis: the root's position channel for that axis when it has one,
//   otherwise the root OFFSET for that axis.
// - A joint may list 0 to 6 distinct channels; a joint without CHANNELS has none.
// - One ROOT per file; at most one End Site per joint.
// Every problem in the text is an InvalidArgument status "<file>:<line>: <problem>" (frame
// problems also name the 0-based frame index). Without a line: text over kMaxBvhFileBytes
// (InvalidArgument), a file that cannot be opened (NotFound) or read (DataLoss), and running
// out of memory (ResourceExhausted). Nothing throws.
#ifndef MODSKILL_SERVER_CORE_MOTION_BVH_PARSER_H_
#define MODSKILL_SERVER_CORE_MOTION_BVH_PARSER_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

// Limits that keep a malformed or hostile file from exhausting memory.
inline constexpr int kMaxBvhJoints = 1000;
inline constexpr int64_t kMaxBvhFileBytes = int64_t{512} << 20;

struct BvhJoint {
  std::string name;
  int parent = -1;                                   // index into BvhClip::joints, -1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // OFFSET in file units, parent frame
  // Canonical names in file order, e.g. {"Xposition", ..., "Zrotation", "Yrotation", "Xrotation"}.
  std::vector<std::string> channels;
  bool has_end_site = false;
  Eigen::Vector3d end_site_offset = Eigen::Vector3d::Zero();
};

struct BvhClip {
  std::vector<BvhJoint> joints;  // file order (depth first): parents before children
  int num_frames = 0;
  double frame_time = 0;                           // seconds
  std::vector<Eigen::Vector3d> root_translation;   // [num_frames], file units
  std::vector<Eigen::Quaterniond> local_rotation;  // [num_frames * joints.size()], row = frame

  int num_joints() const { return static_cast<int>(joints.size()); }
  const Eigen::Quaterniond& LocalRotation(int frame, int joint) const {
    return local_rotation[static_cast<size_t>(frame) * joints.size() + joint];
  }
  // -1 when absent.
  int JointIndex(absl::string_view name) const;
};

// file_name only labels error messages.
absl::StatusOr<BvhClip> ParseBvh(absl::string_view text, absl::string_view file_name);
absl::StatusOr<BvhClip> ReadBvhFile(const std::string& path);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_BVH_PARSER_H_
