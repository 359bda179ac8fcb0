// How many upcoming reference frames a tracker observes (MimicKit's tar_obs_steps 1..N): the next
// frame, which the PD targets reach, and N - 1 after it, so that the policy sees where the motion
// goes instead of only where it is about to be. Session configs, the learner's flag and policy
// files all carry the count, so its bounds are defined once, here.
#ifndef MODSKILL_COMMON_POLICY_REFERENCE_FRAMES_H_
#define MODSKILL_COMMON_POLICY_REFERENCE_FRAMES_H_

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace modskill {

inline constexpr int kMaxReferenceFrames = 8;

// INVALID_ARGUMENT naming `field` unless frames is in [1, kMaxReferenceFrames].
absl::Status ValidateReferenceFrames(int frames, absl::string_view field);

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_REFERENCE_FRAMES_H_
