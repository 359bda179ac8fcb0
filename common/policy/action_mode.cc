#include "common/policy/action_mode.h"

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

}  // namespace modskill
