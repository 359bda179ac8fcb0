// Open-loop reference tracking: the actions whose PD targets are each env's reference pose at
// its next frame. A baseline policy, and the workload benchmarks and tests drive envs with.
#ifndef MODSKILL_SERVER_CORE_ENV_REFERENCE_ACTIONS_H_
#define MODSKILL_SERVER_CORE_ENV_REFERENCE_ACTIONS_H_

#include <vector>

#include "server/core/env/env_batch.h"

namespace modskill {

// [num_envs, action_size] in part order, clamped to [-1, 1].
std::vector<float> ReferenceActions(const EnvBatch& batch);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_REFERENCE_ACTIONS_H_
