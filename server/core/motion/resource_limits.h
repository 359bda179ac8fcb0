// Bounds on what one input may make the server or a tool allocate: every importer, the clip file
// reader and the npz reader check these before they allocate, so a hostile or damaged file (a
// tiny frame rate, a zip bomb, an absurd name) gets a clear InvalidArgument status instead of
// exhausting memory. The defaults hold every clip of AMASS, CMU and DeepMimic with room to spare;
// binaries may replace them from flags once, before any thread starts (SetDefaultResourceLimits).
#ifndef MODSKILL_SERVER_CORE_MOTION_RESOURCE_LIMITS_H_
#define MODSKILL_SERVER_CORE_MOTION_RESOURCE_LIMITS_H_

#include <cstdint>

namespace modskill {

struct ResourceLimits {
  // Frames in one clip, at its own rate or resampled. A 30 fps clip with kinematics takes about
  // 4.5 KB per frame, a source frame at most 1.4 KB (SMPL-X float64), so one clip stays under
  // ~150 MB at the source rate and, with max_clip_seconds, under ~80 MB at 30 fps.
  int max_clip_frames = 100000;
  // Duration of one clip, (frames - 1) / fps. The longest AMASS takes run a few minutes.
  double max_clip_seconds = 600.0;
  // Highest frame rate a file may declare (lower rates are bounded through max_clip_seconds).
  double max_fps = 10000.0;
  // Bytes an .npz may inflate to, per member and over all members. Inflated members are also
  // converted to double (8 bytes per element), which counts against the per-member bound.
  int64_t max_npz_member_bytes = int64_t{192} << 20;
  int64_t max_decompressed_bytes = int64_t{256} << 20;
  // Characters in a clip name (see clip_name.h); generated variants may add a short suffix.
  int max_name_length = 128;
  // |coordinate| of the root in any frame, metres: beyond it the physics loses precision and an
  // env on the clip would reset every step.
  double max_position = 1e4;
};

// The limits in force in this process: the defaults above unless a binary set others.
const ResourceLimits& DefaultResourceLimits();
// Replaces them; call once at start-up, before any thread reads them.
void SetDefaultResourceLimits(const ResourceLimits& limits);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_RESOURCE_LIMITS_H_
