// Inverse kinematics for one body's position: damped least squares (Wampler 1986; Buss 2004)
// over the hinges of chosen bodies, with a null-space pull toward the starting pose so that a
// redundant arm keeps its posture, and every hinge clamped to its range. Where the target is out
// of reach it ends at the pose that comes closest, e.g. the arm stretched toward it.
#ifndef MODSKILL_SERVER_CORE_SIM_REACH_IK_H_
#define MODSKILL_SERVER_CORE_SIM_REACH_IK_H_

#include <vector>

#include "server/core/sim/body_kinematics.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct ReachIkResult {
  std::vector<double> dof_pos;  // every hinge; only the moved bodies' differ from the start
  double distance = 0;          // from `body` to the target at dof_pos (m)
};

// `dof_pos` holds spec.num_hinges() angles to start from; `moved_bodies` are non-root spec body
// indices whose three hinges the solver turns; `target` is in the world frame.
ReachIkResult SolveReachIk(const HumanoidSpec& spec, const RootState& root, const std::vector<double>& dof_pos,
                           int body, const std::vector<int>& moved_bodies, const Vec3& target);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_REACH_IK_H_
