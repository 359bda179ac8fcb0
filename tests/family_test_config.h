// The small family run the family tests train: the walk over gravity 4-14 m/s^2, 8 envs of 48 steps,
// tiny networks, P(a) fitted every iteration.
#ifndef MODSKILL_TESTS_FAMILY_TEST_CONFIG_H_
#define MODSKILL_TESTS_FAMILY_TEST_CONFIG_H_

#include <string>

#include "absl/strings/str_cat.h"
#include "learner/family/family_trainer.h"

namespace modskill::learner::family {

inline FamilyTrainerConfig SmallFamilyConfig(int port, const std::string& run_dir) {
  FamilyTrainerConfig config;
  config.client.server = absl::StrCat("127.0.0.1:", port);
  config.clip = "deepmimic_walk";
  config.ranges = {{"gravity", 4, 14}};
  config.run_dir = run_dir;
  config.num_envs = 8;
  config.horizon = 48;
  config.epochs = 1;
  config.minibatches = 2;
  config.net_every = 1;
  config.policy_hidden = {32};
  config.value_hidden = {32};
  config.curriculum.params_per_batch = 4;
  config.curriculum.episodes_per_param = 1;
  return config;
}

// An untrained policy falls before the walk's end; one that hurries through the clip (tau = 0.25:
// 1.45 frames a step) reaches it first, so its episodes are elite candidates. (At tau = 1, e
// frames a step, the paper's torque limits no longer carry the walk to its end.)
inline void HurryThroughTheClip(FamilyTrainer& trainer) {
  torch::NoGradGuard no_grad;
  trainer.model()->named_parameters()["policy.2.bias"][69] = 0.25;  // the last layer's tau
}

}  // namespace modskill::learner::family

#endif  // MODSKILL_TESTS_FAMILY_TEST_CONFIG_H_
