#include "common/policy/termination.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

absl::Status ValidateTerminationDistance(double distance) {
  if (!(std::isfinite(distance) && distance > 0 && distance <= kMaxTerminationDistance)) {
    return absl::InvalidArgumentError(
        absl::StrCat("termination_distance: ", distance, " m outside (0, ", kMaxTerminationDistance, "]"));
  }
  return absl::OkStatus();
}

absl::StatusOr<TerminationBodies> ParseTerminationBodies(absl::string_view name) {
  if (name == "all") return TerminationBodies::kAll;
  if (name == "no_feet") return TerminationBodies::kNoFeet;
  return absl::InvalidArgumentError(absl::StrCat("'", name.substr(0, 64), "' is not all or no_feet"));
}

std::vector<std::string> TerminationBodiesNames() { return {"all", "no_feet"}; }

}  // namespace modskill
