#include "learner/family/elite_set.h"

#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {

EliteSet::EliteSet(int dims, int64_t frames, int64_t outputs, EliteSetConfig config)
    : frames_(frames), outputs_(outputs), config_(config), tree_(dims) {}

absl::Status EliteSet::CheckOffer(absl::Span<const double> params, double fitness,
                                  const torch::Tensor& trajectory) const {
  if (static_cast<int>(params.size()) != dims()) {
    return absl::InvalidArgumentError(absl::StrCat("elite set: params have ", params.size(), " values, expected ", dims()));
  }
  for (size_t i = 0; i < params.size(); ++i) {
    if (!(params[i] >= 0 && params[i] <= 1)) {
      return absl::InvalidArgumentError(absl::StrCat("elite set: normalized param ", i, " = ", params[i], " outside [0, 1]"));
    }
  }
  if (!std::isfinite(fitness)) return absl::InvalidArgumentError(absl::StrCat("elite set: fitness ", fitness, " is not finite"));
  if (!trajectory.defined() || trajectory.dim() != 2 || trajectory.size(0) != frames_ || trajectory.size(1) != outputs_) {
    return absl::InvalidArgumentError(absl::StrCat("elite set: trajectory must be [", frames_, ", ", outputs_, "]"));
  }
  if (!torch::isfinite(trajectory).all().item<bool>()) {
    return absl::InvalidArgumentError("elite set: trajectory has a non-finite entry");
  }
  return absl::OkStatus();
}

absl::StatusOr<bool> EliteSet::Offer(absl::Span<const double> params, double fitness, const torch::Tensor& trajectory) {
  if (absl::Status s = CheckOffer(params, fitness, trajectory); !s.ok()) return s;
  const std::vector<Neighbor> rivals = tree_.WithinRadius(params, config_.replace_radius);
  for (const Neighbor& rival : rivals) {
    if (elites_[rival.id].fitness >= fitness) return false;
  }
  for (const Neighbor& rival : rivals) {
    tree_.Remove(rival.id);
    elites_[rival.id] = Elite{};
    free_ids_.push_back(rival.id);
  }
  int64_t id = static_cast<int64_t>(elites_.size());
  if (!free_ids_.empty()) {
    id = free_ids_.back();
    free_ids_.pop_back();
  } else {
    elites_.emplace_back();
  }
  elites_[id] = Elite{std::vector<double>(params.begin(), params.end()), fitness,
                      trajectory.detach().to(torch::kFloat32).clone()};
  if (absl::Status s = tree_.Insert(id, params); !s.ok()) return s;
  return true;
}

std::vector<int64_t> EliteSet::Ids() const {
  std::vector<int64_t> ids;
  ids.reserve(size());
  for (int64_t id = 0; id < static_cast<int64_t>(elites_.size()); ++id) {
    if (elites_[id].trajectory.defined()) ids.push_back(id);
  }
  return ids;
}

}  // namespace modskill::learner::family
