// How the humanoid is simulated: rates, PD flavour, contacts.
#ifndef MODSKILL_SERVER_CORE_SIM_PHYSICS_OPTIONS_H_
#define MODSKILL_SERVER_CORE_SIM_PHYSICS_OPTIONS_H_

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/servo_settings.h"  // ValidatePdGainScale, the mode names

namespace modskill {

enum class PdMode {
  // MuJoCo position actuators (kp) with the PD damping (kd) as joint damping, which MuJoCo's
  // Euler integrator treats implicitly: one mj_step per substep, nothing computed by hand.
  kPositionImplicitDamping,
  // Stable PD (Tan, Liu, Turk 2011): torques predicted one step ahead with the mass matrix,
  // computed every substep and applied as generalized forces.
  kStablePd,
};

absl::string_view PdModeName(PdMode mode);
absl::StatusOr<PdMode> ParsePdMode(absl::string_view name);
// OK when `substeps` (physics steps per control step) is in [1, 100]; otherwise an error naming `what`.
absl::Status ValidateSubsteps(int substeps, absl::string_view what);

struct PhysicsOptions {
  double control_hz = 30.0;
  int substeps = 4;  // physics at control_hz * substeps
  PdMode pd_mode = PdMode::kPositionImplicitDamping;
  // Multiplies every hinge's kp and kd (the spec's, PHC's). Measured on the walk: 2 x tracks far
  // worse, and the open-loop reference falls as early at 1-3 x (README, "Learning").
  double pd_gain_scale = 1.0;
  // Residual PD targets lead the reference by kd / kp times its hinge rate: the servo then damps
  // the error to the reference's velocity, kp (q* - q) + kd (qdot_ref - qdot), instead of braking
  // every motion toward rest (a PD tracking a moving target lags it by kd / kp x its rate).
  // Tracking and goal-task sessions; a motor-skill family's displaced, time-warped reference has
  // no rate to lead by, so its sessions ignore it.
  bool damp_to_reference_rate = false;
  bool self_collision = true;  // PHC collides every pair of bodies except parent and child
  bool fixed_root = false;     // weld the pelvis in the air (PD tests, visualization)
  double friction = 1.0;
  double armature = 0.01;      // PHC's joint armature; also keeps light hands stable
  double fixed_root_height = 1.2;
  // A free standing box after the humanoid (the strike task's target, "strike_target"): its
  // joint comes after the humanoid's in qpos/qvel, so the humanoid's indices do not move.
  bool strike_target = false;
  // A static box on the floor ("family_obstacle", part of the world body, so qpos does not grow)
  // for motor-skill family sessions with obstacle parameters. It is built parked below the floor;
  // each episode places and sizes it in the env's own model copy (family_episode.h).
  bool family_obstacle = false;

  double physics_dt() const { return 1.0 / (control_hz * substeps); }
  double control_dt() const { return 1.0 / control_hz; }
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_PHYSICS_OPTIONS_H_
