// One reference motion on the 24-body skeleton, sampled at a fixed rate.
#ifndef MODSKILL_SERVER_CORE_MOTION_MOTION_CLIP_H_
#define MODSKILL_SERVER_CORE_MOTION_MOTION_CLIP_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/resource_limits.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/rotation_math.h"

namespace modskill {

struct MotionClip {
  std::string name;          // unique within a library, e.g. "deepmimic_walk"
  std::string label;         // short text caption
  std::string humanml3d_id;  // e.g. "012181", empty when none
  std::string source;        // where it came from (file, license)
  double fps = 30.0;
  int num_frames = 0;
  int num_bodies = 0;

  // The motion itself: pelvis position and, per body, its rotation relative to its parent
  // (body 0: the pelvis's world rotation). Index [frame * num_bodies + body].
  std::vector<Vec3> root_pos;
  std::vector<Quat> local_rot;

  // Derived by ComputeClipKinematics: world body positions, rotations, linear and angular
  // velocities [frame * num_bodies + body], and hinge angles and rates [frame * num_hinges + h].
  std::vector<Vec3> body_pos;
  std::vector<Quat> body_rot;
  std::vector<Vec3> body_vel;
  std::vector<Vec3> body_ang_vel;
  std::vector<double> dof_pos;
  std::vector<double> dof_vel;

  double duration() const { return num_frames > 1 ? (num_frames - 1) / fps : 0.0; }
  int num_hinges() const { return 3 * (num_bodies - 1); }
  const Quat& local(int frame, int body) const { return local_rot[frame * num_bodies + body]; }
  Quat& local(int frame, int body) { return local_rot[frame * num_bodies + body]; }
};

// Checks sizes, the frame rate and duration against `limits`, finite numbers, root positions
// within limits.max_position and unit quaternions; the message names the clip, field and frame.
absl::Status ValidateClip(const MotionClip& clip, const ResourceLimits& limits = DefaultResourceLimits());

// The one check of a declared rate before anything is sized from it: fps finite in
// (0, limits.max_fps], num_frames <= limits.max_clip_frames and (num_frames - 1) / fps <=
// limits.max_clip_seconds. `field` names where the rate came from, e.g. "Frame Time 0.5".
absl::Status ValidateClipTiming(double fps, int64_t num_frames, absl::string_view field,
                                const ResourceLimits& limits = DefaultResourceLimits());

// Forward kinematics with the spec's offsets, finite-difference velocities and hinge angles
// (MuJoCo's x-y-z hinge order). Needs root_pos and local_rot.
absl::Status ComputeClipKinematics(const HumanoidSpec& spec, MotionClip* clip);

// Resamples root_pos/local_rot to `fps` (linear / slerp); derived fields are cleared. Fails,
// before allocating, when the resampled clip would break `limits`.
absl::StatusOr<MotionClip> ResampleClip(const MotionClip& clip, double fps,
                                        const ResourceLimits& limits = DefaultResourceLimits());

// Lowest point of the collision geometry in one frame (needs body_pos/body_rot).
double LowestGeomPoint(const HumanoidSpec& spec, const MotionClip& clip, int frame);

// Which floor PlaceOnGround puts a clip on (floor_height.h).
enum class FloorMode {
  kWindow,  // FloorHeights: a low quantile of the lowest points around each frame
  kStance,  // and then pinned to the supporting foot wherever one carries the body
};

// Shifts each frame vertically by the floor under it (floor_height.h: a slowly varying height
// that the clip's contacts touch, never above a frame's lowest geometry point), so that the
// contacts rest on z = 0 and no frame is in the ground; then recomputes kinematics.
absl::Status PlaceOnGround(const HumanoidSpec& spec, MotionClip* clip, FloorMode mode = FloorMode::kWindow);

// Fraction of frames with a foot (ankle or toe geometry) within `threshold` of the ground.
double FootContactRatio(const HumanoidSpec& spec, const MotionClip& clip, double threshold = 0.03);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_MOTION_CLIP_H_
