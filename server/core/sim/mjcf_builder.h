// Writes the MJCF of a humanoid from its spec, so that proportions and masses can change at run
// time without a hand-edited XML file.
#ifndef MODSKILL_SERVER_CORE_SIM_MJCF_BUILDER_H_
#define MODSKILL_SERVER_CORE_SIM_MJCF_BUILDER_H_

#include <string>

#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/physics_options.h"

namespace modskill {

// The strike task's target (PhysicsOptions::strike_target): body, joint and geom name, and its
// half extents (m).
inline constexpr char kStrikeTargetName[] = "strike_target";
inline constexpr double kStrikeTargetHalfExtents[3] = {0.2, 0.2, 0.9};
// A family session's obstacle geom (PhysicsOptions::family_obstacle).
inline constexpr char kFamilyObstacleName[] = "family_obstacle";

std::string BuildHumanoidMjcf(const HumanoidSpec& spec, const PhysicsOptions& options);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_MJCF_BUILDER_H_
