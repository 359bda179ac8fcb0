// Maps a policy's action to the hinges' PD targets in the session's ActionMode
// (common/policy/action_mode.h says what each mode means).
#ifndef MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_
#define MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_

#include "common/policy/action_mode.h"
#include "server/core/env/env_spec.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

// Writes pd_targets[h] for every hinge from `action` (spec.action_size values, part order,
// clamped to [-1, 1]). `reference_dof` holds the reference's hinge angles at the next frame
// (read in residual mode only), `reference_rate` its hinge rates there (residual mode, read only
// when the humanoid's PhysicsOptions::damp_to_reference_rate is set).
void MapActionToPdTargets(const ActionMapping& mapping, const HumanoidModel& humanoid, const EnvSpec& spec,
                          const float* action, const double* reference_dof, const double* reference_rate,
                          double* pd_targets);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_ACTION_MAPPING_H_
