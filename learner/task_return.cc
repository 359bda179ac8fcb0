#include "learner/task_return.h"

#include <limits>

namespace modskill::learner {

TaskReturn::TaskReturn(const std::vector<std::string>& reward_terms, int max_episode_steps)
    : episode_steps_(TaskEpisodeSteps(max_episode_steps)) {
  std::vector<double> goal;
  for (const std::string& term : reward_terms) {
    const bool counts = term != "energy";
    goal.push_back(counts ? 1.0 : 0.0);
    if (counts) goal_columns_.push_back(static_cast<int64_t>(goal.size()) - 1), goal_names_.push_back(term);
  }
  goal_terms_ = torch::tensor(goal, torch::kFloat64);
}

torch::Tensor TaskReturn::GoalReward(const torch::Tensor& terms) const {
  TORCH_CHECK(terms.dim() == 2 && terms.size(1) == goal_terms_.size(0), "TaskReturn: expected reward terms [n, ",
              goal_terms_.size(0), "], got ", terms.sizes());
  return terms.to(torch::kFloat64).matmul(goal_terms_);
}

double MeanOrNan(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

}  // namespace modskill::learner
