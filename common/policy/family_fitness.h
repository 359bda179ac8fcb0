// The fitness F of an episode (Lee et al. 2021; DESIGN.md section 4): how good a motion it made,
// as an elite for its parameters a. Unlike the reward it judges the whole episode's motion:
//   F = f_pose f_velocity f_contact f_drag + 0.1 r_constraint.
// DESIGN.md fixes sigma_pose 2.67, sigma_velocity 75.5, sigma_contact 1.3, sigma_drag 0.7 and
// V = 0.5 but not the terms' forms. Our reading, stated once here:
//   f_x = exp(-e_x / sigma_x), e_x the per-frame mean of the error x over the episode (a mean,
//   so that a time warp that lengthens the episode is not punished for its length);
//   pose:     mean over the hinges of (q_h - q^_h)^2, rad^2 (the reference at the warped phase);
//   velocity: mean over the hinges of (w_h - w^_h)^2, (rad/s)^2 (hence sigma 75.5);
//   (means over the degrees of freedom, not sums, as in the authors' public code: a sum over our
//   69 hinges put F near 0 for every motion);
//   contact:  sum over the feet on the floor in the simulation or the reference of
//             (5 (z_foot - z^_foot))^2, m^2 (the authors' code's graded form);
//   drag:     sum over feet in contact at both ends of the control step of max(0, v - V), m/s,
//             v the foot's horizontal displacement over the step / its duration: a planted foot
//             may slip up to V = 0.5 m/s before it counts as dragged;
//   r_constraint in [0, 1]: how well the episode met its parameter's constraint (the task's own
//             measure, e.g. exp of the jump height's error), weighted 0.1.
#ifndef MODSKILL_COMMON_POLICY_FAMILY_FITNESS_H_
#define MODSKILL_COMMON_POLICY_FAMILY_FITNESS_H_

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"

namespace modskill {

struct FitnessConstants {
  double sigma_pose = 2.67;
  double sigma_velocity = 75.5;
  double sigma_contact = 1.3;
  double sigma_drag = 0.7;
  double drag_speed = 0.5;          // V, m/s
  double constraint_weight = 0.1;
};

// One control frame's measurements (see the header comment for units).
struct FitnessFrame {
  double pose_error = 0;
  double velocity_error = 0;
  double contact_error = 0;
  absl::Span<const double> contact_foot_speeds;  // horizontal speed of each foot in contact, m/s
};

struct Fitness {
  double f_pose = 0, f_velocity = 0, f_contact = 0, f_drag = 0;
  double r_constraint = 0;
  double value = 0;  // F
};

// Sums an episode's frames; allocation-free per frame.
class FitnessAccumulator {
 public:
  explicit FitnessAccumulator(FitnessConstants constants = {}) : constants_(constants) {}

  // INVALID_ARGUMENT, naming the field, for a negative or non-finite measurement.
  absl::Status AddFrame(const FitnessFrame& frame);
  // F of the frames so far. FAILED_PRECONDITION with no frame; INVALID_ARGUMENT for an
  // r_constraint outside [0, 1].
  absl::StatusOr<Fitness> Finish(double r_constraint) const;

  int frames() const { return frames_; }

 private:
  FitnessConstants constants_;
  int frames_ = 0;
  double pose_ = 0, velocity_ = 0, contact_ = 0, drag_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_FAMILY_FITNESS_H_
