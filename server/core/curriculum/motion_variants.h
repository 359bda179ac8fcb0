// ModSkill's built-in generator for generative resampling (docs/DESIGN.md section 3, "Active skill
// learning"): new clips from a failed clip without a GPU or an external text-to-motion model.
// It follows the motion displacement mapping and time warping of Lee et al. 2021 (docs/DESIGN.md
// section 4): m'(t) = (m_0 (+) d)(phi(t)), with
//   - d: a smooth, bounded exp-map displacement per joint, q'_j = q_j * exp(d_j(t)), from random
//     knots joined by smoothstep segments (a convex blend, so |d_j(t)| <= rotation_amplitude);
//   - phi: a monotonic time warp from variant time to parent time, phi' = exp(tau) =
//     1 + time_warp_amplitude * w with w smooth in [-1, 1] over the clip's phase (random knots
//     again), so |speed - 1| <= time_warp_amplitude; resampled at the parent's fps.
//
// Whole-body variants (part = -1) displace every joint (every non-root body) and warp time;
// part-level variants displace only one part's joints and do not warp time, so every other
// part's local rotations are bit-identical to the parent's, frame by frame.
//
// What is never displaced: the root (pelvis world rotation and root translation). They carry the
// clip's heading, path and balance; a warp resamples them and only the contact handling below
// changes them. Root translation is shared data, owned by no part: a part-level variant whose part
// holds the pelvis (e.g. "Torso" of the 5-part layout) leaves it alone, but the contact handling
// of a leg variant moves it even though the legs do not own it.
//
// Post-processing, in order:
//   1. Joint limits: each displaced body's local rotation is decomposed into MuJoCo's intrinsic
//      x-y-z hinge angles, clamped to the spec's [range_low, range_high] and rebuilt. Bodies that
//      are not displaced are not touched (no round trip), so they keep the parent's angles even
//      where those are out of range.
//   2. Contacts, when a leg changes (whole body, or a part with a body on a foot's chain; in the
//      shipped layouts the parts holding L_Ankle or R_Ankle): the root is moved so that the
//      variant keeps the parent's contacts: vertically, per frame by a smooth correction (within
//      1 cm of the exact one), so that the lowest geometry point follows the parent's (at the
//      warped time); horizontally, so that a foot the parent has planted stays planted (one
//      planted foot is pinned exactly; two share the error). Where a foot still slides on the
//      floor (e.g. a swinging foot lowered onto it), the displaced legs' displacements are faded
//      out around that frame, a few rounds at most (contact-aware attenuation), so that the legs
//      tend to the parent's motion there.
//   3. Kinematics are computed (ComputeClipKinematics).
// Variants are not filtered here: CheckPlausibility (plausibility_filter.h) does that.
//
// Deterministic: the same parent, layout and options give bit-identical variants.
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_MOTION_VARIANTS_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_MOTION_VARIANTS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"

namespace modskill {

// The name GenerateVariants writes into VariantProvenance::generator.
inline constexpr char kBuiltinVariantGenerator[] = "builtin_displacement";

struct VariantOptions {
  int count = 3;                      // variants per request, [1, 64]
  int part = -1;                      // -1: whole body; else an index into layout.parts (part-level variant)
  uint64_t seed = 0;                  // variant k of a request draws from its own stream of (seed, k)
  double rotation_amplitude = 0.35;   // rad, peak joint displacement |d| (exp-map), [0, 1.5]
  double time_warp_amplitude = 0.25;  // max relative speed change |phi' - 1|, [0, 0.9]; whole body only
  int knots = 4;                      // random knots per displacement / warp curve over the clip, [2, 64]
};

struct VariantProvenance {
  std::string parent;     // the parent clip's name
  std::string generator;  // kBuiltinVariantGenerator
  int part = -1;          // VariantOptions::part
  uint64_t seed = 0;      // VariantOptions::seed of the request (the variant's index is in its name)
};

struct MotionVariant {
  MotionClip clip;
  VariantProvenance provenance;
};

// `options.count` variants of `parent`, named "<parent>~<w|part name>~<k>" (k = 0, 1, ...), with
// the parent's label and text id, a source that says how they were made, the parent's fps and
// computed kinematics. Whole-body variants last round(warped duration * fps) + 1 frames (duration
// within [1/(1+a), 1/(1-a)] of the parent's); part-level variants as many frames as the parent.
// Errors (INVALID_ARGUMENT) name the field: count, part, rotation_amplitude, time_warp_amplitude,
// knots, or the parent (no kinematics, fewer than 2 frames, another skeleton).
absl::StatusOr<std::vector<MotionVariant>> GenerateVariants(const HumanoidSpec& spec, const PartLayout& layout,
                                                           const MotionClip& parent, const VariantOptions& options);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_MOTION_VARIANTS_H_
