// Points given in the heading frame on the root's ground point (x forward, y left, z height above
// the floor): the frame reach targets and strike targets are drawn in, shared so that the tasks
// and the held reach poses made for them mean the same point.
#ifndef MODSKILL_SERVER_CORE_SIM_HEADING_FRAME_H_
#define MODSKILL_SERVER_CORE_SIM_HEADING_FRAME_H_

#include "server/core/sim/rotation_math.h"

namespace modskill {

inline Vec3 HeadingGroundPointToWorld(const Vec3& root_pos, const Quat& root_rot, const Vec3& local) {
  const Vec3 ground(root_pos.x(), root_pos.y(), 0.0);
  return ground + HeadingRotation(root_rot) * local;
}

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_HEADING_FRAME_H_
