#include "server/core/env/action_mapping.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

absl::Status ActionMapping::Validate(absl::string_view field) const {
  if (mode == ActionMode::kResidual && !(std::isfinite(residual_scale) && residual_scale > 0 &&
                                         residual_scale <= kMaxResidualScale)) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": ", residual_scale, " must be finite and in (0, ", kMaxResidualScale, "]"));
  }
  return absl::OkStatus();
}

const char* ActionModeName(ActionMode mode) { return mode == ActionMode::kResidual ? "residual" : "absolute"; }

absl::StatusOr<ActionMode> ParseActionMode(absl::string_view name) {
  if (name == "absolute") return ActionMode::kAbsolute;
  if (name == "residual") return ActionMode::kResidual;
  return absl::InvalidArgumentError(absl::StrCat("unknown action mode '", name.substr(0, 64),
                                                 "' (absolute or residual)"));
}

std::vector<std::string> ActionModeNames() { return {"absolute", "residual"}; }

void MapActionToPdTargets(const ActionMapping& mapping, const HumanoidModel& humanoid, const EnvSpec& spec,
                          const float* action, const double* reference_dof, double* pd_targets) {
  const std::vector<double>& offset = humanoid.action_offset();
  const std::vector<double>& scale = humanoid.action_scale();
  for (int a = 0; a < spec.action_size; ++a) {
    const int h = spec.action_hinge[a];
    const double clamped = std::clamp(static_cast<double>(action[a]), -1.0, 1.0);
    if (mapping.mode == ActionMode::kAbsolute) {
      pd_targets[h] = offset[h] + scale[h] * clamped;
    } else {
      // The range is offset +- half of it; scale = min(1.2 * half range, pi).
      const BodySpec& body = humanoid.spec().body(1 + h / 3);
      const double target = reference_dof[h] + mapping.residual_scale * scale[h] * clamped;
      pd_targets[h] = std::clamp(target, body.range_low[h % 3], body.range_high[h % 3]);
    }
  }
}

}  // namespace modskill
