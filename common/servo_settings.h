// The servo settings' allowed values, in one place: the PD modes by name and the range of the
// gain scale. The server's flags (server/core/sim/physics_options) and a policy file's physics
// record (common/policy/physics_settings) refuse the same values in the same words.
#ifndef MODSKILL_COMMON_SERVO_SETTINGS_H_
#define MODSKILL_COMMON_SERVO_SETTINGS_H_

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace modskill {

// The PD modes as flags, spec fields and policy files name them.
inline constexpr absl::string_view kPdModePositionImplicit = "position_implicit";
inline constexpr absl::string_view kPdModeStablePd = "stable_pd";
// Both names, for an error message.
inline constexpr absl::string_view kPdModeChoices = "position_implicit or stable_pd";

bool IsPdModeName(absl::string_view name);

// OK when `scale` (the factor on every hinge's kp and kd) is finite, in (0, 100]; otherwise
// INVALID_ARGUMENT naming `what` (a field or a flag).
absl::Status ValidatePdGainScale(double scale, absl::string_view what);

}  // namespace modskill

#endif  // MODSKILL_COMMON_SERVO_SETTINGS_H_
