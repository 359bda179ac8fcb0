// The PPO step size decayed linearly over env steps (the anneal of Schulman et al. 2017's Atari
// runs, Stable-Baselines3's linear schedule): learning_rate at step 0, learning_rate x
// floor_fraction from decay_steps on, so that late updates move a policy near its optimum less.
// On the walk at 1.64 M steps it cost training reward and did not steady the evaluation (README,
// "Learning"): off by default. decay_steps == 0 keeps the rate constant.
#ifndef MODSKILL_LEARNER_LEARNING_RATE_DECAY_H_
#define MODSKILL_LEARNER_LEARNING_RATE_DECAY_H_

#include <torch/torch.h>

#include <cstdint>

namespace modskill::learner {

struct LearningRateDecay {
  double learning_rate = 1e-4;
  int64_t decay_steps = 0;
  double floor_fraction = 0.1;

  // The rate after `env_steps` env steps of training (a resumed run counts its earlier steps).
  double RateAt(int64_t env_steps) const;
};

// Writes `rate` into every parameter group of `optimizer`.
void SetLearningRate(torch::optim::Adam& optimizer, double rate);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_LEARNING_RATE_DECAY_H_
