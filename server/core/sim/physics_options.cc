#include "server/core/sim/physics_options.h"

#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace modskill {

absl::string_view PdModeName(PdMode mode) {
  switch (mode) {
    case PdMode::kPositionImplicitDamping:
      return "position_implicit";
    case PdMode::kStablePd:
      return "stable_pd";
  }
  return "unknown";
}

absl::StatusOr<PdMode> ParsePdMode(absl::string_view name) {
  if (name == "position_implicit") return PdMode::kPositionImplicitDamping;
  if (name == "stable_pd") return PdMode::kStablePd;
  return absl::InvalidArgumentError(
      absl::StrCat("pd_mode: unknown value '", name, "' (expected position_implicit or stable_pd)"));
}

absl::Status ValidatePdGainScale(double scale, absl::string_view what) {
  if (std::isfinite(scale) && scale > 0 && scale <= 100) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(what, ": ", scale, " must be finite, in (0, 100]"));
}

absl::Status ValidateSubsteps(int substeps, absl::string_view what) {
  if (substeps >= 1 && substeps <= 100) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(what, ": ", substeps, " outside [1, 100]"));
}

}  // namespace modskill
