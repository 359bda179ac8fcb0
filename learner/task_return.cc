#include "learner/task_return.h"

#include <limits>

namespace modskill::learner {

TaskReturn::TaskReturn(const std::vector<std::string>& reward_terms, int max_episode_steps)
    : num_terms_(static_cast<int64_t>(reward_terms.size())), episode_steps_(TaskEpisodeSteps(max_episode_steps)) {
  std::vector<int64_t> columns;
  for (size_t k = 0; k < reward_terms.size(); ++k) {
    if (reward_terms[k] == "energy") continue;
    columns.push_back(static_cast<int64_t>(k));
    goal_names_.push_back(reward_terms[k]);
  }
  goal_columns_ = torch::tensor(columns, torch::kInt64);
}

torch::Tensor TaskReturn::GoalTerms(const torch::Tensor& terms) const {
  TORCH_CHECK(terms.dim() == 2 && terms.size(1) == num_terms_, "TaskReturn: expected reward terms [n, ", num_terms_,
              "], got ", terms.sizes());
  return terms.to(torch::kFloat64).index_select(1, goal_columns_);
}

double MeanOrNan(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

}  // namespace modskill::learner
