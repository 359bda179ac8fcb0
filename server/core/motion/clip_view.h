// The viewer's plain numbers (common/viewer) from the humanoid spec and its clips: the
// collision geometry exactly as the MJCF builder writes it (one geom per body, body frame) and
// a clip's world body poses as the reference track.
#ifndef MODSKILL_SERVER_CORE_MOTION_CLIP_VIEW_H_
#define MODSKILL_SERVER_CORE_MOTION_CLIP_VIEW_H_

#include <vector>

#include "absl/status/statusor.h"
#include "common/viewer/viewer_scene.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

std::vector<ViewerBody> ViewerBodiesFromSpec(const HumanoidSpec& spec);

// body_pos/body_rot of every frame (ComputeClipKinematics must have run) as float32.
ViewerTrack ViewerTrackFromPoses(const std::vector<Vec3>& body_pos, const std::vector<Quat>& body_rot,
                                 ViewerTrack::Role role);

// The clip as the page's reference character; fails when it has no frames or its kinematics
// were not computed (the message names the clip).
absl::StatusOr<ViewerClip> ViewerClipFromMotion(const MotionClip& clip);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_CLIP_VIEW_H_
