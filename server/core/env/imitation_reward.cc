#include "server/core/env/imitation_reward.h"

#include <algorithm>
#include <cmath>

namespace modskill {

TrackingErrors ComputeImitationTerms(const ImitationRewardConfig& config, const HumanoidState& sim,
                                     const HumanoidState& reference, float* terms, double* body_distance) {
  const int bodies = static_cast<int>(sim.body_pos.size());
  TrackingErrors errors;
  for (int b = 0; b < bodies; ++b) {
    const double distance = (reference.body_pos[b] - sim.body_pos[b]).norm();
    if (body_distance != nullptr) body_distance[b] = distance;
    errors.max_body_distance = std::max(errors.max_body_distance, distance);
    errors.mean_body_distance += distance;
  }
  errors.mean_body_distance /= bodies;
  double pos_sq = 0, rot_sq = 0, vel_sq = 0, ang_vel_sq = 0;
  const auto add_body = [&](int b) {
    pos_sq += (reference.body_pos[b] - sim.body_pos[b]).squaredNorm();
    const double angle = RotationAngle(reference.body_rot[b] * sim.body_rot[b].conjugate());
    rot_sq += angle * angle;
    vel_sq += (reference.body_vel[b] - sim.body_vel[b]).squaredNorm();
    ang_vel_sq += (reference.body_ang_vel[b] - sim.body_ang_vel[b]).squaredNorm();
  };
  if (config.bodies.empty()) {
    for (int b = 0; b < bodies; ++b) add_body(b);
  } else {
    for (int b : config.bodies) add_body(b);
  }
  const int rewarded = config.bodies.empty() ? bodies : static_cast<int>(config.bodies.size());
  // PHC averages squared errors over bodies and, for vectors, over their 3 components.
  const double per_component = 1.0 / (3.0 * rewarded);
  terms[kRewardPos] = static_cast<float>(config.w_pos * std::exp(-config.k_pos * pos_sq * per_component));
  terms[kRewardRot] = static_cast<float>(config.w_rot * std::exp(-config.k_rot * rot_sq / rewarded));
  terms[kRewardVel] = static_cast<float>(config.w_vel * std::exp(-config.k_vel * vel_sq * per_component));
  terms[kRewardAngVel] = static_cast<float>(config.w_ang_vel * std::exp(-config.k_ang_vel * ang_vel_sq * per_component));
  return errors;
}

}  // namespace modskill
