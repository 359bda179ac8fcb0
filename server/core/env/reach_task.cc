#include "server/core/env/reach_task.h"

#include <cmath>

namespace modskill {

void ReachTask::DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double x = unit(rng), y = unit(rng), z = 1.0 + unit(rng);
  // The box is centred in the heading frame on the root's ground point; z is height above ground.
  Vec3 ground = sim.body_pos[0];
  ground.z() = 0;
  target_ = ground + HeadingRotation(sim.body_rot[0]) * Vec3(x, y, z);
}

void ReachTask::Reward(const HumanoidState& sim, const mjData* data, float* terms) {
  terms[0] = static_cast<float>(std::exp(-5.0 * (sim.body_pos[context_->right_hand] - target_).squaredNorm()));
}

void ReachTask::WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const {
  const Vec3 local = InverseHeadingRotation(sim.body_rot[0]) * (target_ - sim.body_pos[0]);
  goal[0] = static_cast<float>(local.x());
  goal[1] = static_cast<float>(local.y());
  goal[2] = static_cast<float>(local.z());
}

}  // namespace modskill
