// PHC's imitation reward and the energy penalty (docs/DESIGN.md section 3), term by term.
#ifndef MODSKILL_SERVER_CORE_ENV_IMITATION_REWARD_H_
#define MODSKILL_SERVER_CORE_ENV_IMITATION_REWARD_H_

#include <vector>

#include "server/core/env/env_spec.h"
#include "server/core/env/humanoid_state.h"

namespace modskill {

struct ImitationRewardConfig {
  // r = w_p e^{-k_p mse_p} + w_r e^{-k_r mse_r} + w_v e^{-k_v mse_v} + w_w e^{-k_w mse_w}
  double k_pos = 100, k_rot = 10, k_vel = 0.1, k_ang_vel = 0.1;
  double w_pos = 0.5, w_rot = 0.3, w_vel = 0.1, w_ang_vel = 0.1;
  // The bodies the four terms average over (spec indices, sorted, each once;
  // SessionConfig.reward_parts); empty: every body. A part retrained alone is rewarded for its own bodies, so the frozen parts'
  // errors do not drown its signal.
  std::vector<int> bodies;
  // The four terms compare each rewarded body in the root's frame (SessionConfig.
  // reward_relative_to_root): a part's own motion, without the root's drift the other parts cause.
  bool relative_to_root = false;
  // Power penalty -c * sum |tau * qdot|, off for the first frames after a reset.
  double energy_coefficient = 0.0005;
  int energy_free_steps = 3;
};

struct TrackingErrors {
  double max_body_distance = 0;   // m
  double mean_body_distance = 0;  // m
};

// Fills terms[kRewardPos..kRewardAngVel] (weighted, over config.bodies) and returns the body
// distance errors over every body; when `body_distance` is given, also each body's distance (m)
// there, for termination and per-part errors.
TrackingErrors ComputeImitationTerms(const ImitationRewardConfig& config, const HumanoidState& sim,
                                     const HumanoidState& reference, float* terms, double* body_distance = nullptr);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_IMITATION_REWARD_H_
