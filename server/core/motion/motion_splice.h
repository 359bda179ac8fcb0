// Motion splicing: one clip's body with some parts' motion taken from another clip (Heck, Kovar
// and Gleicher 2006, without their posture alignment). It makes the "new data" of issue 13's
// item 4: a part retrained on motion the frozen parts already know, e.g. the walk with the
// arms of a jog or a punch.
#ifndef MODSKILL_SERVER_CORE_MOTION_MOTION_SPLICE_H_
#define MODSKILL_SERVER_CORE_MOTION_MOTION_SPLICE_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

// How the source's time maps onto the base's frames.
enum class SpliceTiming {
  kStretch,  // the whole source over the base's duration (one source cycle per base cycle)
  kClip,     // the source at its own speed from its first frame, held at its last frame
  // One source pose (at SpliceRequest::hold_at) held for the whole base, reached from the base's
  // own pose over the first kHoldRampSeconds: skills that hold a hand somewhere, which a reach
  // needs and clips whose arms never stop do not teach.
  kHold,
};
inline constexpr double kHoldRampSeconds = 1.0;

// The held pose's share of frame `frame` of a clip at `fps`: a smoothstep from 0 to 1 over
// kHoldRampSeconds, so the ramp starts and ends at rest.
double HoldRampWeight(double fps, int frame);

absl::StatusOr<SpliceTiming> ParseSpliceTiming(absl::string_view name);

struct SpliceRequest {
  std::string name;                // the new clip's name (ValidateClipName)
  std::vector<int> source_bodies;  // spec body indices whose local rotations come from the source
  SpliceTiming timing = SpliceTiming::kStretch;
  double hold_at = 0.5;  // kHold: the held pose's time, a share of the source's duration in [0, 1]
  std::string label;  // the new clip's caption; empty: the base's, "with <bodies> from <source>"
};

// The base's root path and every other body's local rotation, frame for frame; each body in
// request.source_bodies rotates relative to its parent as in the source, at the source time the
// timing gives (slerp between the source's frames). The root (body 0) cannot be taken from the
// source: its rotation carries the base's travel. Both clips must have the spec's bodies and the
// same frame rate. The result is placed on the ground and has its kinematics computed; its
// source field names both clips' sources.
absl::StatusOr<MotionClip> SpliceParts(const HumanoidSpec& spec, const MotionClip& base, const MotionClip& source,
                                       const SpliceRequest& request);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_MOTION_SPLICE_H_
