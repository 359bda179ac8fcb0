// Preallocated batch tensors that envs write their rows into (EnvPool style): one contiguous
// float32 block per field, row i belonging to env i. Shipped as is, never gathered.
#ifndef MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_
#define MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_

#include <cstdint>
#include <vector>

#include "server/core/env/env_spec.h"

namespace modskill {

struct BatchBuffers {
  int num_envs = 0;
  std::vector<float> obs;           // [N, obs_size]; part p of env i: obs[i*obs_size + part_obs[p].start ...]
  std::vector<float> amp_obs;       // [N, amp_obs_size], newest frame first
  std::vector<float> reward;        // [N]
  std::vector<float> reward_terms;  // [N, kNumRewardTerms]
  std::vector<uint8_t> done;        // [N] episode ended (terminated or truncated); the row holds the next episode's obs
  std::vector<uint8_t> truncated;   // [N] ended by the clip's end or the step limit, not by failure
  std::vector<int32_t> clip_id;     // [N] clip the row's obs refers to
  std::vector<int32_t> frame;       // [N] reference frame of the row's state
  std::vector<int32_t> ended_clip_id;  // [N] clip of the episode that ended (valid where done)
  std::vector<int32_t> ended_frame;    // [N] frame at which it ended
  std::vector<float> max_body_error;   // [N] m, before any reset
  std::vector<float> mean_body_error;  // [N] m
  int num_parts = 0;
  std::vector<float> part_error;       // [N, num_parts] mean body distance per part (layout order), m, before any reset

  void Allocate(const EnvSpec& spec, int envs) {
    num_envs = envs;
    obs.assign(static_cast<size_t>(envs) * spec.obs_size, 0.f);
    amp_obs.assign(static_cast<size_t>(envs) * spec.amp_obs_size, 0.f);
    reward.assign(envs, 0.f);
    reward_terms.assign(static_cast<size_t>(envs) * kNumRewardTerms, 0.f);
    done.assign(envs, 0);
    truncated.assign(envs, 0);
    clip_id.assign(envs, 0);
    frame.assign(envs, 0);
    ended_clip_id.assign(envs, -1);
    ended_frame.assign(envs, -1);
    max_body_error.assign(envs, 0.f);
    mean_body_error.assign(envs, 0.f);
    num_parts = spec.layout.num_parts();
    part_error.assign(static_cast<size_t>(envs) * num_parts, 0.f);
  }
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_
