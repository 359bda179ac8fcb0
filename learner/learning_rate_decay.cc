#include "learner/learning_rate_decay.h"

#include <algorithm>

namespace modskill::learner {

double LearningRateDecay::RateAt(int64_t env_steps) const {
  if (decay_steps <= 0) return learning_rate;
  const double progress = std::clamp(static_cast<double>(env_steps) / static_cast<double>(decay_steps), 0.0, 1.0);
  return learning_rate * (1.0 - progress * (1.0 - floor_fraction));
}

void SetLearningRate(torch::optim::Adam& optimizer, double rate) {
  for (torch::optim::OptimizerParamGroup& group : optimizer.param_groups()) {
    static_cast<torch::optim::AdamOptions&>(group.options()).lr(rate);
  }
}

}  // namespace modskill::learner
