// Importers from the motion formats of the field onto the 24-body humanoid:
// AMASS/SMPL(-H) .npz, CMU BVH, DeepMimic humanoid3d .txt, and the native .msclip.
#ifndef MODSKILL_SERVER_CORE_MOTION_MOTION_IMPORT_H_
#define MODSKILL_SERVER_CORE_MOTION_MOTION_IMPORT_H_

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/bvh_parser.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/motion/resource_limits.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct ImportOptions {
  double target_fps = 30.0;     // the control rate
  bool place_on_ground = true;  // lowest geometry over the clip touches z = 0
  FloorMode floor = FloorMode::kWindow;  // the floor it is placed on (motion_clip.h)
  std::string name;             // default: derived from the file name; checked by ValidateClipName
  std::string label;
  std::string humanml3d_id;
  ResourceLimits limits = DefaultResourceLimits();  // frames, duration, npz sizes, name length
};

// Picks the importer from the extension (and, for .txt, the content), resamples, grounds and
// computes kinematics. Errors name the file and the field. The clip's name (options.name, the
// name stored in an .msclip, or the one derived from the file name) must pass ValidateClipName.
absl::StatusOr<MotionClip> ImportMotionFile(const std::string& path, const HumanoidSpec& spec,
                                            const ImportOptions& options = {});

// The raw importers: clip at the file's own rate, on the humanoid, kinematics not yet computed.
// Each checks the file's declared rate and frame count with ValidateClipTiming before sizing
// anything from them.
absl::StatusOr<MotionClip> ImportAmassNpz(const std::string& path, const HumanoidSpec& spec,
                                          const ResourceLimits& limits = DefaultResourceLimits());
// Drops the leading calibration frame CMU takes start with (see LeadingCalibrationFrames).
absl::StatusOr<MotionClip> ImportCmuBvh(const std::string& path, const HumanoidSpec& spec,
                                        const ResourceLimits& limits = DefaultResourceLimits());
// How many leading frames of `bvh` are a calibration pose: each differs from the next by far more
// than the take then moves per frame.
int LeadingCalibrationFrames(const BvhClip& bvh);
absl::StatusOr<MotionClip> ImportDeepMimic(const std::string& path, const HumanoidSpec& spec,
                                           const ResourceLimits& limits = DefaultResourceLimits());
absl::StatusOr<MotionClip> ImportDeepMimicText(absl::string_view text, absl::string_view what,
                                               const HumanoidSpec& spec,
                                               const ResourceLimits& limits = DefaultResourceLimits());

// "humanoid3d_walk.txt" -> "deepmimic_walk", "02_01.bvh" -> "cmu_02_01", "x.npz" -> "x"; characters
// a clip name may not hold become '_' (SanitizeClipName).
std::string DefaultClipName(const std::string& path);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_MOTION_IMPORT_H_
