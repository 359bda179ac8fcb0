// What one training iteration passes between its phases (collect -> returns -> policy and
// discriminator updates -> summary). Private to the Trainer's own files: trainer.cc (the
// iteration), trainer_collect.cc, trainer_update.cc and trainer_checkpoint.cc.
#ifndef MODSKILL_LEARNER_TRAINER_PHASES_H_
#define MODSKILL_LEARNER_TRAINER_PHASES_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "learner/server_pool.h"
#include "learner/trainer.h"

namespace modskill::learner {

// One session's share of an iteration's experience, [T, n, ...].
struct Trainer::SlotRollout {
  SessionSlot* slot = nullptr;
  int n = 0;
  bool failed = false;
  // actions: what PPO sampled, [T, n, sample_size] (the actions sent in tracking; z-space
  // samples in a task run, ModSkillPolicyImpl::SampleMean).
  torch::Tensor obs, actions, log_prob, values, task_reward, dones, truncated, amp_next;
  torch::Tensor next_obs;  // observation after the last step (raw)
  std::vector<torch::Tensor> raw_obs;  // for the normalizer, after the update
  torch::Tensor reward_terms_sum;
  // Task runs: the normalized returns (TaskProgress) of the episodes that ended in this rollout.
  std::vector<double> normalized_returns;
  EpisodeEnds ends;  // why those episodes ended
};

// One collection: every live session's rollout, and what it ran under.
struct Trainer::Collection {
  std::vector<SlotRollout> rollouts;
  double termination_distance = 0;
  int64_t policy_version = 0;  // of the weights that acted
};

// The iteration's experience from every usable session, flattened to [T * N, ...].
struct Trainer::TrainingBatch {
  torch::Tensor obs;  // normalized with the statistics of the iteration's start
  torch::Tensor actions, old_log_prob, old_values, advantages, returns;  // actions: PPO's samples
  torch::Tensor raw_obs;      // for the normalizer
  // AMP observations of live (not ended) rows drawn at random for the discriminator,
  // [amp_samples * discriminator_epochs, M]: copying all T * N rows of 2320 floats cost more
  // than the discriminator step itself.
  torch::Tensor policy_amp;
  double task_sum = 0, amp_sum = 0, samples = 0;
  torch::Tensor terms_sum;
  int live_sessions = 0;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TRAINER_PHASES_H_
