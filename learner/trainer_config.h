// Everything a training run is configured with; written into every checkpoint.
#ifndef MODSKILL_LEARNER_TRAINER_CONFIG_H_
#define MODSKILL_LEARNER_TRAINER_CONFIG_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "learner/model_config.h"

namespace modskill::learner {

struct TrainerConfig {
  // Where to simulate.
  std::vector<std::string> servers;
  std::string token;
  std::string tls_ca_file;
  int envs_per_server = 256;
  int sessions_per_server = 2;      // two halves per server overlap simulation with inference
  std::string part_layout = "5part";
  std::vector<std::string> motions;  // clip names; empty: the server's whole library
  double server_timeout_s = 120;     // exit when no server answers for this long

  // What to learn with.
  ModelConfig model;
  int iterations = 100;
  int horizon = 32;             // steps per env per iteration (PHC)
  int epochs = 5;
  int minibatch_size = 2048;
  // Small preset. With sigma = exp(-2.9) PPO's ratios are steep: at 1e-4 about 80 % of the
  // samples clip, 3e-4 diverges (KL ~ 30); the paper's 2e-5 suits its 3072-env GPU batches.
  double learning_rate = 1e-4;
  double gamma = 0.99;
  double lambda = 0.95;
  double clip_ratio = 0.2;
  double value_clip = 0.2;
  double value_coefficient = 2.0;
  double max_grad_norm = 1.0;
  double task_reward_weight = 0.5;  // PHC: task and AMP rewards 0.5 / 0.5
  double amp_reward_weight = 0.5;
  double discriminator_learning_rate = 1e-4;
  double gradient_penalty_weight = 5.0;
  int discriminator_epochs = 2;
  int amp_samples = 2048;  // expert and policy samples per discriminator epoch
  uint64_t seed = 1;
  int report_every = 5;  // iterations between failure reports to the servers' samplers; 0: never

  // Where results go.
  std::string run_dir;
  int checkpoint_every = 10;  // iterations
  bool resume = false;

  static absl::StatusOr<TrainerConfig> ForPreset(const std::string& preset);
  absl::Status Validate() const;
  std::string ToJson() const;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TRAINER_CONFIG_H_
