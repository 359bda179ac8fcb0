#include "server/core/env/action_mapping.h"

#include <algorithm>
#include <cmath>

namespace modskill {

void MapActionToPdTargets(const ActionMapping& mapping, const HumanoidModel& humanoid, const EnvSpec& spec,
                          const float* action, const double* reference_dof, const double* reference_rate,
                          double* pd_targets) {
  const std::vector<double>& offset = humanoid.action_offset();
  const bool lead = humanoid.options().damp_to_reference_rate && reference_rate != nullptr;
  const std::vector<double>& scale = humanoid.action_scale();
  // The hinges' actions; a family session's time warp comes after them (spec.time_warp_action).
  const int hinge_actions = static_cast<int>(spec.action_hinge.size());
  for (int a = 0; a < hinge_actions; ++a) {
    const int h = spec.action_hinge[a];
    const double clamped = std::clamp(static_cast<double>(action[a]), -1.0, 1.0);
    if (mapping.mode == ActionMode::kAbsolute) {
      pd_targets[h] = offset[h] + scale[h] * clamped;
    } else {
      // The range is offset +- half of it; scale = min(1.2 * half range, pi).
      const BodySpec& body = humanoid.spec().body(1 + h / 3);
      double target = reference_dof[h] + mapping.residual_scale * scale[h] * clamped;
      if (lead) target += humanoid.kd()[h] / humanoid.kp()[h] * reference_rate[h];
      pd_targets[h] = mapping.clamp_to_joint_range ? std::clamp(target, body.range_low[h % 3], body.range_high[h % 3])
                                                   : target;
    }
  }
}

}  // namespace modskill
