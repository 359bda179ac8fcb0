#include "common/task_settings.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

std::string TaskSettings::WireFieldName(absl::string_view field) { return absl::StrCat("task_settings.", field); }

absl::Status TaskSettings::Validate(const FieldNamer& name) const {
  if (!std::isfinite(min_speed) || min_speed < 0 || min_speed > 10) {
    return absl::InvalidArgumentError(absl::StrCat(name("min_speed"), ": ", min_speed, " outside [0, 10] m/s"));
  }
  if (!std::isfinite(max_speed) || max_speed < min_speed || max_speed > 10) {
    return absl::InvalidArgumentError(
        absl::StrCat(name("max_speed"), ": ", max_speed, " outside [min_speed = ", min_speed, ", 10] m/s"));
  }
  if (!std::isfinite(min_goal_interval_s) || min_goal_interval_s <= 0 || min_goal_interval_s > 3600) {
    return absl::InvalidArgumentError(
        absl::StrCat(name("min_goal_interval_s"), ": ", min_goal_interval_s, " outside (0, 3600] s"));
  }
  if (!std::isfinite(max_goal_interval_s) || max_goal_interval_s < min_goal_interval_s ||
      max_goal_interval_s > 3600) {
    return absl::InvalidArgumentError(absl::StrCat(name("max_goal_interval_s"), ": ", max_goal_interval_s,
                                                   " outside [min_goal_interval_s = ", min_goal_interval_s,
                                                   ", 3600] s"));
  }
  if (!std::isfinite(reach_box_size) || reach_box_size <= 0 || reach_box_size > 4) {
    return absl::InvalidArgumentError(
        absl::StrCat(name("reach_box_size"), ": ", reach_box_size, " outside (0, 4] m"));
  }
  const double half = 0.5 * reach_box_size;
  constexpr const char* kCenterFields[3] = {"reach_center_x", "reach_center_y", "reach_center_z"};
  for (int axis = 0; axis < 3; ++axis) {
    const double low = axis == 2 ? 0.0 : -3.0;
    const double c = reach_center[axis];
    if (!std::isfinite(c) || c - half < low || c + half > 3.0) {
      return absl::InvalidArgumentError(absl::StrCat(name(kCenterFields[axis]), ": ", c,
                                                     " puts the reach box (edge ", reach_box_size,
                                                     " m) outside [", low, ", 3] m"));
    }
  }
  if (!std::isfinite(steering_rate) || steering_rate < 0 || steering_rate > kMaxSteeringRate) {
    return absl::InvalidArgumentError(
        absl::StrCat(name("steering_rate"), ": ", steering_rate, " outside [0, ", kMaxSteeringRate, "] deg/s"));
  }
  return absl::OkStatus();
}

}  // namespace modskill
