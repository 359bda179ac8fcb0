// The check every clip-making tool (splice, reach poses) runs on the clips it builds from: one
// body per skeleton body, and at least two frames (a clip needs a velocity).
#ifndef MODSKILL_SERVER_CORE_MOTION_CLIP_FITS_SKELETON_H_
#define MODSKILL_SERVER_CORE_MOTION_CLIP_FITS_SKELETON_H_

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

// INVALID_ARGUMENT "TOOL: clip 'NAME' has B bodies and F frames; ..." unless `clip` fits `spec`.
inline absl::Status CheckClipFitsSkeleton(const HumanoidSpec& spec, const MotionClip& clip, absl::string_view tool) {
  if (clip.num_bodies == spec.num_bodies() && clip.num_frames >= 2) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(tool, ": clip '", clip.name, "' has ", clip.num_bodies, " bodies and ",
                                                 clip.num_frames, " frames; the skeleton has ", spec.num_bodies(),
                                                 " bodies and a clip needs 2 frames"));
}

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_CLIP_FITS_SKELETON_H_
