#include "server/core/sim/physics_options.h"

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace modskill {

absl::string_view PdModeName(PdMode mode) {
  switch (mode) {
    case PdMode::kPositionImplicitDamping:
      return kPdModePositionImplicit;
    case PdMode::kStablePd:
      return kPdModeStablePd;
  }
  return "unknown";
}

absl::StatusOr<PdMode> ParsePdMode(absl::string_view name) {
  if (name == kPdModePositionImplicit) return PdMode::kPositionImplicitDamping;
  if (name == kPdModeStablePd) return PdMode::kStablePd;
  return absl::InvalidArgumentError(absl::StrCat("pd_mode: unknown value '", name, "' (expected ", kPdModeChoices, ")"));
}

absl::Status ValidateSubsteps(int substeps, absl::string_view what) {
  if (substeps >= 1 && substeps <= 100) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(what, ": ", substeps, " outside [1, 100]"));
}

}  // namespace modskill
