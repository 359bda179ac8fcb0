// When a task env's humanoid has fallen (steer, reach): a body other than the feet touches the
// floor, or the root sinks below a height. Tracking ends episodes by distance to the reference
// instead.
#ifndef MODSKILL_SERVER_CORE_ENV_FALL_DETECTION_H_
#define MODSKILL_SERVER_CORE_ENV_FALL_DETECTION_H_

#include <vector>

#include <mujoco/mujoco.h>

#include "server/core/env/humanoid_state.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

class FallDetector {
 public:
  static constexpr double kMinRootHeight = 0.3;  // m; the pelvis stands at about 0.9

  explicit FallDetector(const HumanoidModel& humanoid);

  // From the contacts of the last physics step and the state read after it.
  bool Fallen(const mjData* data, const HumanoidState& sim) const;

 private:
  int floor_geom_ = -1;
  std::vector<char> may_touch_floor_;  // per MuJoCo geom: belongs to a foot (or is the floor)
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_FALL_DETECTION_H_
