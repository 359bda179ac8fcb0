// Whether a clip (typically a generated variant, see motion_variants.h) is worth training on:
// cheap kinematic checks for the defects generators produce, plus the AMP discriminator's
// verdict when the caller has one (ModSkill's public code keeps a generated clip only if the
// discriminator scores >= 0.5 on 30 random frames; docs/DESIGN.md section 3).
//
// Checks, in this order; the first that fails is the verdict's reason:
//   joint_limit    every hinge angle (dof_pos) within [range_low - max_limit_violation,
//                  range_high + max_limit_violation]; names the worst hinge and its frame.
//   penetration    the lowest geometry point of every frame >= -max_penetration; names the body
//                  and frame of the deepest point.
//   body_speed     |body_pos[f + 1] - body_pos[f]| * fps <= max_body_speed for every body and
//                  frame (frame-to-frame differences, which a one-frame teleport cannot halve as
//                  central differences would); names the body and the frames.
//   foot_skate     per foot body (ankles and toes), the median horizontal speed (body_vel) over
//                  the frames where its geometry is within 3 cm of the floor <= max_foot_skate;
//                  names the foot, its contact frame count and its fastest contact frame.
//   discriminator  only with scores: the mean of the scores >= min_discriminator_score (scores
//                  must be finite and in [0, 1]); names the lowest-scoring sample.
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_PLAUSIBILITY_FILTER_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_PLAUSIBILITY_FILTER_H_

#include <string>
#include <vector>

#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct PlausibilityOptions {
  double max_limit_violation = 0.02;     // rad beyond a hinge range
  double max_penetration = 0.03;         // m below the floor (lowest geometry point)
  double max_foot_skate = 0.6;           // m/s horizontal speed of a foot while it is within 3 cm of the floor
                                         // (median over contact frames)
  double max_body_speed = 15.0;          // m/s, any body, any frame (velocity spikes)
  double min_discriminator_score = 0.5;  // used only when scores are given
};

struct PlausibilityVerdict {
  bool accepted = false;
  // Empty when accepted; else "<check>: <body or joint> ... at frame <f> ...", <check> one of
  // joint_limit, penetration, body_speed, foot_skate, discriminator, invalid (a clip that does
  // not fit the skeleton or whose kinematics cannot be computed).
  std::string reason;
};

// A foot is in contact while its geometry is this close to the floor (m), as in FootContactRatio.
inline constexpr double kFootContactHeight = 0.03;
// foot_skate judges a foot over at least this many contact frames: a plant lasts longer than one.
inline constexpr size_t kMinPlantFrames = 2;

// Lowest z of one body's geometry in one frame (needs body_pos/body_rot); the per-body form of
// LowestGeomPoint.
double BodyGeomBottom(const HumanoidSpec& spec, const MotionClip& clip, int frame, int body);

// Computes the kinematics on a copy when `clip` has none. `discriminator_scores`: scores in
// [0, 1] of sampled frames (e.g. 30 random ones); null skips that check.
PlausibilityVerdict CheckPlausibility(const HumanoidSpec& spec, const MotionClip& clip,
                                      const PlausibilityOptions& options,
                                      const std::vector<float>* discriminator_scores = nullptr);

// A generated clip judged against the clip it was made from: it may not be worse than its
// parent by more than the options' margins. Retargeted data has defects of its own (knees a few
// degrees past PHC's ranges, a little floor penetration or skating); a variant is refused for
// what the generator added, not for what it inherited: per hinge, the parent's largest range
// violation + max_limit_violation; max_penetration raised to the parent's deepest point + 1 cm;
// max_body_speed and max_foot_skate to 1.25 x the parent's.
PlausibilityVerdict CheckVariantPlausibility(const HumanoidSpec& spec, const MotionClip& variant,
                                             const MotionClip& parent, const PlausibilityOptions& options,
                                             const std::vector<float>* discriminator_scores = nullptr);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_PLAUSIBILITY_FILTER_H_
