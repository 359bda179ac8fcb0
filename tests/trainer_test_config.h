// The small trainer configuration the learner tests train with: two sessions of 16 envs per
// server, a few iterations, one update thread; the walk skills task tests train a head over, and the
// small task evaluation they run after.
#ifndef MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_
#define MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "learner/task_evaluation.h"
#include "learner/trainer.h"
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

// A proprioceptive tracker of the walk trained for one iteration in `run_dir`: skills a task head
// can drive. The path of its policy.pt.
inline absl::StatusOr<std::string> TrainWalkSkills(const std::vector<std::string>& servers, const std::string& run_dir) {
  TrainerConfig config = SmallTestTrainerConfig(servers, run_dir);
  config.motions = {"deepmimic_walk"};
  config.iterations = 1;
  config.model.controller_input = ModelConfig::ControllerInput::kProprioception;
  auto tracker = Trainer::Create(config);
  if (!tracker.ok()) return tracker.status();
  if (absl::Status status = (*tracker)->Run(); !status.ok()) return status;
  return run_dir + "/policy.pt";
}

// Four episodes of `task` on the walk, of at most `max_episode_steps`, in the residual mode of
// `config` (the run that trained the policy).
inline TaskEvaluationOptions SmallTaskEvaluation(const std::string& task, const TrainerConfig& config,
                                                 int max_episode_steps) {
  TaskEvaluationOptions options;
  options.session.set_task(task);
  options.session.add_motions("deepmimic_walk");
  options.session.set_action_mode(v1::RESIDUAL);
  options.session.set_residual_scale(static_cast<float>(config.residual_scale));
  options.session.set_max_episode_steps(max_episode_steps);
  options.episodes = 4;
  return options;
}

}  // namespace modskill::learner

#endif  // MODSKILL_TESTS_TRAINER_TEST_CONFIG_H_
