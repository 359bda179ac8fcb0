#include "common/wire/policy_enums.h"

#include "absl/strings/str_cat.h"

namespace modskill {

v1::ActionMode ToWire(ActionMode mode) { return mode == ActionMode::kResidual ? v1::RESIDUAL : v1::ABSOLUTE; }

v1::TerminationBodies ToWire(TerminationBodies bodies) {
  return bodies == TerminationBodies::kNoFeet ? v1::NO_FEET : v1::ALL;
}

absl::StatusOr<ActionMode> ActionModeFromWire(v1::ActionMode mode) {
  switch (mode) {
    case v1::ACTION_MODE_UNSPECIFIED:
    case v1::ABSOLUTE:
      return ActionMode::kAbsolute;
    case v1::RESIDUAL:
      return ActionMode::kResidual;
    default:
      return absl::InvalidArgumentError(absl::StrCat("action_mode: unknown value ", static_cast<int>(mode)));
  }
}

absl::StatusOr<TerminationBodies> TerminationBodiesFromWire(v1::TerminationBodies bodies) {
  switch (bodies) {
    case v1::TERMINATION_BODIES_UNSPECIFIED:
    case v1::ALL:
      return TerminationBodies::kAll;
    case v1::NO_FEET:
      return TerminationBodies::kNoFeet;
    default:
      return absl::InvalidArgumentError(absl::StrCat("termination_bodies: unknown value ", static_cast<int>(bodies)));
  }
}

}  // namespace modskill
