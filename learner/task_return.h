// The figure of a task run (skill reuse benchmark): an episode's normalized return, the sum of
// its reward terms other than "energy" divided by the session's max_episode_steps. Every task's
// non-energy terms sum to at most 1 per step, so it lies in [0, 1] for an episode that lasts
// the whole session limit and falls short when the character falls early or misses its goal.
#ifndef MODSKILL_LEARNER_TASK_RETURN_H_
#define MODSKILL_LEARNER_TASK_RETURN_H_

#include <string>
#include <vector>

#include <torch/torch.h>

#include "common/policy/task_episode.h"

namespace modskill::learner {

class TaskReturn {
 public:
  // reward_terms: the session's (EnvSpec.reward_terms); max_episode_steps 0: the default.
  TaskReturn(const std::vector<std::string>& reward_terms, int max_episode_steps);

  // terms: [n, K] (StepResult.reward_terms) -> [n, G] float64, the non-energy terms (goal_names()).
  torch::Tensor GoalTerms(const torch::Tensor& terms) const;
  // terms: [n, K] -> [n] float64, the sum of the non-energy terms.
  torch::Tensor GoalReward(const torch::Tensor& terms) const { return GoalTerms(terms).sum(1); }
  // An episode's summed GoalReward -> its normalized return.
  double Normalize(double goal_return) const { return goal_return / episode_steps_; }
  int episode_steps() const { return episode_steps_; }
  // The names of GoalTerms' columns, in the session's order.
  const std::vector<std::string>& goal_names() const { return goal_names_; }

 private:
  int64_t num_terms_;            // K
  torch::Tensor goal_columns_;   // [G] int64: every column but energy's
  std::vector<std::string> goal_names_;
  int episode_steps_;
};

// The mean of `values`; NaN when there are none (no episode ended).
double MeanOrNan(const std::vector<double>& values);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TASK_RETURN_H_
