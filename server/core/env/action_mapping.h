// How a policy's action a in [-1, 1] becomes the PD targets of the hinges.
//   absolute: target = offset + scale * a (PHC, the ModSkill paper): the policy must produce the
//             whole pose, and a = 0 holds every joint at its range midpoint.
//   residual: target = reference pose of the next frame + residual_scale * scale * a, clamped to
//             the hinge's range (Lee et al. 2021's displacement of the reference): a = 0 is
//             open-loop tracking, and the policy learns only the correction.
#ifndef MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_
#define MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/env/env_spec.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

enum class ActionMode { kAbsolute, kResidual };

inline constexpr double kDefaultResidualScale = 0.5;
inline constexpr double kMaxResidualScale = 10;

struct ActionMapping {
  ActionMode mode = ActionMode::kAbsolute;
  double residual_scale = kDefaultResidualScale;  // residual only

  // residual_scale finite and in (0, kMaxResidualScale]; the message names `field`.
  absl::Status Validate(absl::string_view field = "residual_scale") const;
};

// "absolute", "residual".
const char* ActionModeName(ActionMode mode);
absl::StatusOr<ActionMode> ParseActionMode(absl::string_view name);
std::vector<std::string> ActionModeNames();

// Writes pd_targets[h] for every hinge from `action` (spec.action_size values, part order,
// clamped to [-1, 1]). `reference_dof` holds the reference's hinge angles at the next frame
// (read in residual mode only).
void MapActionToPdTargets(const ActionMapping& mapping, const HumanoidModel& humanoid, const EnvSpec& spec,
                          const float* action, const double* reference_dof, double* pd_targets);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_
