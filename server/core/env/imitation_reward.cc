#include "server/core/env/imitation_reward.h"

#include <algorithm>
#include <cmath>

namespace modskill {
namespace {

// A body's pose and motion as the reward compares them: in the world, or, given the root's
// inverse rotation, seen from the root (body 0), which is what a part does on its own.
struct ComparedBody {
  Vec3 pos, vel, ang_vel;
  Quat rot;
};

ComparedBody Compared(const HumanoidState& state, int b, const Quat* to_root) {
  if (to_root == nullptr) return {state.body_pos[b], state.body_vel[b], state.body_ang_vel[b], state.body_rot[b]};
  return {*to_root * (state.body_pos[b] - state.body_pos[0]), *to_root * (state.body_vel[b] - state.body_vel[0]),
          *to_root * (state.body_ang_vel[b] - state.body_ang_vel[0]), *to_root * state.body_rot[b]};
}

}  // namespace

TrackingErrors ComputeImitationTerms(const ImitationRewardConfig& config, const HumanoidState& sim,
                                     const HumanoidState& reference, float* terms, double* body_distance) {
  const int bodies = static_cast<int>(sim.body_pos.size());
  const auto rewarded = [&](int b) {
    return config.bodies.empty() || std::binary_search(config.bodies.begin(), config.bodies.end(), b);
  };
  const Quat reference_to_root = reference.body_rot[0].conjugate(), sim_to_root = sim.body_rot[0].conjugate();
  const Quat* reference_frame = config.relative_to_root ? &reference_to_root : nullptr;
  const Quat* sim_frame = config.relative_to_root ? &sim_to_root : nullptr;
  TrackingErrors errors;
  double pos_sq = 0, rot_sq = 0, vel_sq = 0, ang_vel_sq = 0;
  for (int b = 0; b < bodies; ++b) {
    const double distance_sq = (reference.body_pos[b] - sim.body_pos[b]).squaredNorm();
    const double distance = std::sqrt(distance_sq);
    if (body_distance != nullptr) body_distance[b] = distance;
    errors.max_body_distance = std::max(errors.max_body_distance, distance);
    errors.mean_body_distance += distance;
    if (!rewarded(b)) continue;
    const ComparedBody ref = Compared(reference, b, reference_frame), own = Compared(sim, b, sim_frame);
    pos_sq += config.relative_to_root ? (ref.pos - own.pos).squaredNorm() : distance_sq;
    const double angle = RotationAngle(ref.rot * own.rot.conjugate());
    rot_sq += angle * angle;
    vel_sq += (ref.vel - own.vel).squaredNorm();
    ang_vel_sq += (ref.ang_vel - own.ang_vel).squaredNorm();
  }
  errors.mean_body_distance /= bodies;
  const int rewarded_bodies = config.bodies.empty() ? bodies : static_cast<int>(config.bodies.size());
  // PHC averages squared errors over bodies and, for vectors, over their 3 components.
  const double per_component = 1.0 / (3.0 * rewarded_bodies);
  terms[kRewardPos] = static_cast<float>(config.w_pos * std::exp(-config.k_pos * pos_sq * per_component));
  terms[kRewardRot] = static_cast<float>(config.w_rot * std::exp(-config.k_rot * rot_sq / rewarded_bodies));
  terms[kRewardVel] = static_cast<float>(config.w_vel * std::exp(-config.k_vel * vel_sq * per_component));
  terms[kRewardAngVel] = static_cast<float>(config.w_ang_vel * std::exp(-config.k_ang_vel * ang_vel_sq * per_component));
  return errors;
}

}  // namespace modskill
