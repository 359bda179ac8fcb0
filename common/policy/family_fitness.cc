#include "common/policy/family_fitness.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

absl::Status CheckMeasure(const char* name, double value) {
  if (!(std::isfinite(value) && value >= 0)) {
    return absl::InvalidArgumentError(absl::StrCat("fitness frame: ", name, " ", value, " is not a finite value >= 0"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status FitnessAccumulator::AddFrame(const FitnessFrame& frame) {
  if (absl::Status s = CheckMeasure("pose_error", frame.pose_error); !s.ok()) return s;
  if (absl::Status s = CheckMeasure("velocity_error", frame.velocity_error); !s.ok()) return s;
  if (absl::Status s = CheckMeasure("contact_error", frame.contact_error); !s.ok()) return s;
  double drag = 0;
  for (double speed : frame.contact_foot_speeds) {
    if (absl::Status s = CheckMeasure("contact_foot_speeds", speed); !s.ok()) return s;
    drag += std::max(0.0, speed - constants_.drag_speed);
  }
  pose_ += frame.pose_error;
  velocity_ += frame.velocity_error;
  contact_ += frame.contact_error;
  drag_ += drag;
  ++frames_;
  return absl::OkStatus();
}

absl::StatusOr<Fitness> FitnessAccumulator::Finish(double r_constraint) const {
  if (frames_ == 0) return absl::FailedPreconditionError("fitness: the episode has no frame");
  if (!(r_constraint >= 0 && r_constraint <= 1)) {
    return absl::InvalidArgumentError(absl::StrCat("fitness: r_constraint ", r_constraint, " outside [0, 1]"));
  }
  const double n = frames_;
  Fitness f;
  f.f_pose = std::exp(-(pose_ / n) / constants_.sigma_pose);
  f.f_velocity = std::exp(-(velocity_ / n) / constants_.sigma_velocity);
  f.f_contact = std::exp(-(contact_ / n) / constants_.sigma_contact);
  f.f_drag = std::exp(-(drag_ / n) / constants_.sigma_drag);
  f.r_constraint = r_constraint;
  f.value = f.f_pose * f.f_velocity * f.f_contact * f.f_drag + constants_.constraint_weight * r_constraint;
  return f;
}

}  // namespace modskill
