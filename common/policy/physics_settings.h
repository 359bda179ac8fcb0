// The simulation a policy was trained in beyond its control step: the physics rate and the
// servos (the server's --substeps, --pd_mode, --pd_gain_scale and --damp_to_reference_rate).
// A policy's actions are PD targets, so the same targets under other servos or at another physics
// rate make another controller: the shipped walk policy, 100 % / 27.9 mm where it was trained,
// falls at 60 Hz, with PD gains x 2 or under stable PD (docs/results/physics_mismatch_2026-12-07).
// Policy files, checkpoints and the env spec every server sends carry these settings, and a run,
// rollout or skill reuse that would mix two is refused by name.
#ifndef MODSKILL_COMMON_POLICY_PHYSICS_SETTINGS_H_
#define MODSKILL_COMMON_POLICY_PHYSICS_SETTINGS_H_

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/servo_settings.h"

namespace modskill {

struct PhysicsSettings {
  double physics_dt = 0;  // s, one physics step; 0: not recorded (files and servers from before)
  std::string pd_mode = std::string(kPdModePositionImplicit);
  double pd_gain_scale = 1;
  bool damp_to_reference_rate = false;

  bool recorded() const { return physics_dt > 0; }

  // A JSON object {"physics_dt", "pd_mode", "pd_gain_scale", "damp_to_reference_rate"}.
  std::string ToJson() const;
  // INVALID_ARGUMENT naming `where` and the field for anything but such an object with physics_dt
  // in (0, 1] s, pd_mode and pd_gain_scale as the server's flags take them (common/servo_settings.h).
  static absl::StatusOr<PhysicsSettings> FromJson(absl::string_view json, absl::string_view where);
};

// The first setting in which `mine` and `theirs` differ, worded for a message: "physics_dt
// 0.00833333 s (120 Hz) against <theirs_name> 0.0166667 s (60 Hz); the server's --substeps sets
// it"; empty when they agree or either is not recorded.
std::string PhysicsDifference(const PhysicsSettings& mine, const PhysicsSettings& theirs, absl::string_view theirs_name);

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_PHYSICS_SETTINGS_H_
