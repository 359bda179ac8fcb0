#include "server/core/env/reference_actions.h"

#include <algorithm>

namespace modskill {

std::vector<float> ReferenceActions(const EnvBatch& batch) {
  const EnvSpec& spec = batch.spec();
  const HumanoidModel& humanoid = batch.humanoid();
  std::vector<float> actions(static_cast<size_t>(batch.num_envs()) * spec.action_size);
  for (int i = 0; i < batch.num_envs(); ++i) {
    const MotionClip& clip = batch.motions().clip(batch.buffers().clip_id[i]);
    const int frame = std::min(batch.buffers().frame[i] + 1, clip.num_frames - 1);
    for (int a = 0; a < spec.action_size; ++a) {
      const int h = spec.action_hinge[a];
      const double target = clip.dof_pos[frame * clip.num_hinges() + h];
      actions[static_cast<size_t>(i) * spec.action_size + a] = static_cast<float>(
          std::clamp((target - humanoid.action_offset()[h]) / humanoid.action_scale()[h], -1.0, 1.0));
    }
  }
  return actions;
}

}  // namespace modskill
