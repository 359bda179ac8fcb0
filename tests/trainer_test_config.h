// The small trainer configuration the learner tests train with: two sessions of 16 envs per
// server, a few iterations, one update thread.
#ifndef MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_
#define MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_

#include <string>
#include <vector>

#include "learner/trainer_config.h"

namespace modskill::learner {

inline TrainerConfig SmallTestTrainerConfig(const std::vector<std::string>& servers, const std::string& run_dir) {
  TrainerConfig config = *TrainerConfig::ForPreset("small");
  config.servers = servers;
  config.envs_per_server = 16;
  config.sessions_per_server = 2;
  config.horizon = 8;
  config.epochs = 2;
  config.minibatch_size = 64;
  config.amp_samples = 64;
  config.discriminator_epochs = 1;
  config.iterations = 2;
  config.run_dir = run_dir;
  config.checkpoint_every = 1;
  config.server_timeout_s = 20;
  // ctest runs other tests beside these: two OpenMP threads each would spin against them.
  config.update_threads = 1;
  return config;
}

}  // namespace modskill::learner

#endif  // MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_
