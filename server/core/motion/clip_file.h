// The native clip format (.msclip): what a clip needs and nothing else, so a library loads fast.
//
//   "MSKCLIP1" | u32 version | u32 num_frames | u32 num_bodies | f64 fps
//   | 4 strings (u32 length + bytes): name, label, humanml3d_id, source
//   | f32 root_pos[num_frames][3] | f32 local_rot[num_frames][num_bodies][4] (w, x, y, z)
//   | u32 crc32 of everything before it
// Little-endian. Derived kinematics are recomputed on load from the skeleton in use.
#ifndef MODSKILL_SERVER_CORE_MOTION_CLIP_FILE_H_
#define MODSKILL_SERVER_CORE_MOTION_CLIP_FILE_H_

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/motion/resource_limits.h"

namespace modskill {

inline constexpr absl::string_view kClipFileExtension = ".msclip";

std::string EncodeClip(const MotionClip& clip);
// `what` names the source in error messages. Derived fields are left empty. The stored name must
// pass ValidateClipName and the header's fps and frame count ValidateClipTiming, before the
// frames are allocated.
absl::StatusOr<MotionClip> DecodeClip(absl::string_view bytes, absl::string_view what,
                                      const ResourceLimits& limits = DefaultResourceLimits());

absl::Status WriteClipFile(const std::string& path, const MotionClip& clip);
// Reads and computes kinematics for `spec`.
absl::StatusOr<MotionClip> ReadClipFile(const std::string& path, const HumanoidSpec& spec,
                                        const ResourceLimits& limits = DefaultResourceLimits());

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_CLIP_FILE_H_
