// How a policy's action a in [-1, 1] becomes the PD targets of the hinges. The mode is part of
// a session's config, of the learner's flags and of every policy file, so it lives here where
// server, learner and client all see it; the mapping itself is server/core/env/action_mapping.h.
//   absolute: target = offset + scale * a (PHC, the ModSkill paper): the policy must produce the
//             whole pose, and a = 0 holds every joint at its range midpoint.
//   residual: target = reference pose of the next frame + residual_scale * scale * a, clamped to
//             the hinge's range (Lee et al. 2021's displacement of the reference): a = 0 is
//             open-loop tracking, and the policy learns only the correction.
#ifndef MODSKILL_COMMON_POLICY_ACTION_MODE_H_
#define MODSKILL_COMMON_POLICY_ACTION_MODE_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

enum class ActionMode { kAbsolute, kResidual };

inline constexpr double kDefaultResidualScale = 0.5;
inline constexpr double kMaxResidualScale = 10;

struct ActionMapping {
  ActionMode mode = ActionMode::kAbsolute;
  double residual_scale = kDefaultResidualScale;  // residual only
  // Residual only: clamp each target into its hinge's range. A motor-skill family does not: a
  // target beyond the range lets the servo keep pushing at full torque to the end of the range
  // (a jump's knees and hips), as the authors' targets (reference + up to 0.7 pi, unclamped) do;
  // the joint's own limit still stops the hinge.
  bool clamp_to_joint_range = true;

  // residual_scale finite and in (0, kMaxResidualScale]; the message names `field`.
  absl::Status Validate(absl::string_view field = "residual_scale") const;
};

// "absolute", "residual".
const char* ActionModeName(ActionMode mode);
absl::StatusOr<ActionMode> ParseActionMode(absl::string_view name);
std::vector<std::string> ActionModeNames();

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_ACTION_MODE_H_
