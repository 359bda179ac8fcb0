// Steer's and reach's goal settings (SessionConfig.task_settings) and their bounds, shared by the
// server, which refuses a session outside them, and the learner, which checks its flags against
// the same bounds before it asks for one (a refused session would only be retried until
// --server_timeout_s).
#ifndef MODSKILL_COMMON_TASK_SETTINGS_H_
#define MODSKILL_COMMON_TASK_SETTINGS_H_

#include <functional>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace modskill {

struct TaskSettings {
  double min_speed = 0.5;  // steer: target speed range (m/s)
  double max_speed = 3.0;
  double min_goal_interval_s = 2.0;  // steer, reach: a new goal after U(min, max) seconds
  double max_goal_interval_s = 5.0;
  // reach: targets are drawn uniformly in a box of this edge (m) centred at reach_center
  // (heading frame on the root's ground point: forward, left, height). The paper's: 2 m at (0, 0, 1).
  double reach_box_size = 2.0;
  double reach_center[3] = {0.0, 0.0, 1.0};
  // steer, reach, strike: the base motion turns toward the goal (steer's direction, the reach
  // point, the strike target) at up to this rate (deg/s), so that skills trained on turning clips
  // read "turn that way" from it; 0: the base motion goes on straight ahead of the character, as
  // the paper's high-level policy must then turn by its z alone.
  double steering_rate = 0.0;
  static constexpr double kMaxSteeringRate = 720.0;

  // How an error names a field ("min_speed", "reach_center_x", ...): the wire's
  // "task_settings.<field>" by default, a flag's name on the learner's side.
  using FieldNamer = std::function<std::string(absl::string_view field)>;
  static std::string WireFieldName(absl::string_view field);

  // INVALID_ARGUMENT naming the field: speeds finite with 0 <= min <= max <= 10, intervals
  // finite with 0 < min <= max <= 3600, the reach box's edge in (0, 4] and the box within 3 m of
  // the root horizontally and between 0 and 3 m high, the steering rate finite in [0, 720] deg/s.
  absl::Status Validate(const FieldNamer& name = WireFieldName) const;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_TASK_SETTINGS_H_
