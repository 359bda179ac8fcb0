#include "common/servo_settings.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

bool IsPdModeName(absl::string_view name) { return name == kPdModePositionImplicit || name == kPdModeStablePd; }

absl::Status ValidatePdGainScale(double scale, absl::string_view what) {
  if (std::isfinite(scale) && scale > 0 && scale <= 100) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(what, ": ", scale, " must be finite, in (0, 100]"));
}

}  // namespace modskill
