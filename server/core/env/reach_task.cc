#include "server/core/env/reach_task.h"

#include <cmath>

#include "server/core/sim/heading_frame.h"

namespace modskill {

void ReachTask::DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  const TaskSettings& settings = context_->settings;
  const double half = 0.5 * settings.reach_box_size;
  std::uniform_real_distribution<double> unit(-half, half);
  const double x = settings.reach_center[0] + unit(rng), y = settings.reach_center[1] + unit(rng),
               z = settings.reach_center[2] + unit(rng);
  // The box is centred in the heading frame on the root's ground point; z is height above ground.
  target_ = HeadingGroundPointToWorld(sim.body_pos[0], sim.body_rot[0], Vec3(x, y, z));
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
