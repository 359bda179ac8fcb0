#include "common/wire/policy_spec_wire.h"

#include <algorithm>

#include "common/wire/physics_wire.h"

namespace modskill {

PolicySpec PolicySpecOf(const v1::EnvSpec& spec, const ActionMapping& action) {
  PolicySpec policy;
  policy.part_layout = spec.part_layout();
  policy.obs_size = spec.obs_size();
  policy.action_size = spec.action_size();
  policy.joint_names.assign(spec.joint_names().begin(), spec.joint_names().end());
  policy.control_dt = spec.control_dt();
  policy.physics = PhysicsOf(spec);
  policy.action = action;
  if (!spec.task().empty()) policy.task = spec.task();
  // A server from before the field sends 0: it showed one frame.
  policy.reference_frames = std::max(1, spec.reference_frames());
  return policy;
}

}  // namespace modskill
