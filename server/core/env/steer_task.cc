#include "server/core/env/steer_task.h"

#include <algorithm>
#include <cmath>

namespace modskill {

void SteerTask::Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) {
  previous_root_ = sim.body_pos[0];
  StartGoal(sim, rng);
}

void SteerTask::DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  const double angle = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
  direction_ = Vec3(std::cos(angle), std::sin(angle), 0);
  speed_ = std::uniform_real_distribution<double>(context_->settings.min_speed, context_->settings.max_speed)(rng);
}

void SteerTask::Reward(const HumanoidState& sim, const mjData* data, float* terms) {
  Vec3 velocity = (sim.body_pos[0] - previous_root_) / context_->control_dt;
  velocity.z() = 0;
  previous_root_ = sim.body_pos[0];
  const double along = direction_.dot(velocity);
  const double tangential = (velocity - along * direction_).squaredNorm();
  const double speed_error = speed_ - along;
  terms[0] = static_cast<float>(0.7 * std::exp(-0.25 * (speed_error * speed_error + 0.1 * tangential)));
  const Vec3 facing = HeadingRotation(sim.body_rot[0]) * Vec3::UnitX();
  terms[1] = static_cast<float>(0.3 * std::max(0.0, facing.dot(direction_)));
}

void SteerTask::WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const {
  const Vec3 local = InverseHeadingRotation(sim.body_rot[0]) * direction_;
  goal[0] = static_cast<float>(local.x());
  goal[1] = static_cast<float>(local.y());
  goal[2] = static_cast<float>(speed_);
}

}  // namespace modskill
