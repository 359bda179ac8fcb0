#include "learner/family/parameter_curriculum.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {
namespace {

absl::Status CheckConfig(const CurriculumConfig& c) {
  const auto bad = [](const char* field, double value, const char* want) {
    return absl::InvalidArgumentError(absl::StrCat("curriculum config: ", field, " ", value, " ", want));
  };
  if (c.params_per_batch < 1) return bad("params_per_batch", c.params_per_batch, "must be >= 1");
  if (c.episodes_per_param < 1) return bad("episodes_per_param", c.episodes_per_param, "must be >= 1");
  if (!(c.explore_density_lo >= 0 && c.explore_density_lo < c.explore_density_hi)) {
    return bad("explore_density_lo", c.explore_density_lo, "must be in [0, explore_density_hi)");
  }
  if (!(c.explore_density_hi <= 1)) return bad("explore_density_hi", c.explore_density_hi, "must be <= 1");
  if (!(c.refine_density_min > 0 && c.refine_density_min <= 1)) return bad("refine_density_min", c.refine_density_min, "must be in (0, 1]");
  if (!(c.value_k > 0)) return bad("value_k", c.value_k, "must be > 0");
  if (!(c.min_exploration_rate >= 0 && c.min_exploration_rate <= 1)) return bad("min_exploration_rate", c.min_exploration_rate, "must be in [0, 1]");
  if (c.refinement_batches < 1) return bad("refinement_batches", c.refinement_batches, "must be >= 1");
  if (c.explore_tries < 1) return bad("explore_tries", c.explore_tries, "must be >= 1");
  if (c.mcmc_steps < 1) return bad("mcmc_steps", c.mcmc_steps, "must be >= 1");
  if (!(c.mcmc_step > 0)) return bad("mcmc_step", c.mcmc_step, "must be > 0");
  if (c.value_mean_samples < 1) return bad("value_mean_samples", c.value_mean_samples, "must be >= 1");
  if (!(c.density.bandwidth > 0)) return bad("density.bandwidth", c.density.bandwidth, "must be > 0");
  if (!(c.density.saturation > 0)) return bad("density.saturation", c.density.saturation, "must be > 0");
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<ParameterCurriculum> ParameterCurriculum::Create(const ParamSpace& space, CurriculumConfig config,
                                                                uint64_t seed) {
  if (absl::Status s = CheckConfig(config); !s.ok()) return s;
  std::vector<bool> free(space.dims());
  for (int i = 0; i < space.dims(); ++i) free[i] = !space.is_constraint(i);
  return ParameterCurriculum(std::move(free), config, seed);
}

ParameterCurriculum::ParameterCurriculum(std::vector<bool> free, CurriculumConfig config, uint64_t seed)
    : free_(std::move(free)), config_(config), rng_(seed), density_(static_cast<int>(free_.size()), config.density) {}

std::vector<double> ParameterCurriculum::UniformDraw() {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> a(free_.size(), 0.0);
  for (size_t i = 0; i < a.size(); ++i) {
    if (free_[i]) a[i] = unit(rng_);
  }
  return a;
}

CurriculumBatch ParameterCurriculum::SampleExploration(int count) {
  CurriculumBatch batch;
  batch.mode = CurriculumMode::kExploration;
  batch.episodes_per_param = config_.episodes_per_param;
  for (int k = 0; k < count; ++k) {
    std::vector<double> best;
    double best_gap = 2;  // how far the draw's density is from the band; 0 inside it
    for (int t = 0; t < config_.explore_tries && best_gap > 0; ++t) {
      std::vector<double> a = UniformDraw();
      const double rho = density_.Evaluate(a);
      const double gap = std::max({0.0, config_.explore_density_lo - rho, rho - config_.explore_density_hi});
      if (gap < best_gap) {
        best_gap = gap;
        best = std::move(a);
      }
    }
    batch.in_band += best_gap == 0 ? 1 : 0;
    batch.params.push_back(std::move(best));
  }
  return batch;
}

absl::StatusOr<std::vector<double>> ParameterCurriculum::Values(const ValueFunction& value,
                                                                const std::vector<std::vector<double>>& params) const {
  std::vector<double> v = value(params);
  if (v.size() != params.size()) {
    return absl::InvalidArgumentError(absl::StrCat("curriculum: the value function returned ", v.size(), " values for ",
                                                   params.size(), " parameter vectors"));
  }
  for (double x : v) {
    if (!std::isfinite(x)) return absl::InvalidArgumentError(absl::StrCat("curriculum: the value function returned ", x));
  }
  return v;
}

absl::StatusOr<double> ParameterCurriculum::MeanVisitedValue(const ValueFunction& value) {
  std::vector<std::vector<double>> visited;
  if (density_.size() <= config_.value_mean_samples) {
    for (int64_t i = 0; i < density_.size(); ++i) visited.push_back(density_.point(i));
  } else {  // an unbiased subsample keeps one critic call small
    std::uniform_int_distribution<int64_t> pick(0, density_.size() - 1);
    for (int i = 0; i < config_.value_mean_samples; ++i) visited.push_back(density_.point(pick(rng_)));
  }
  absl::StatusOr<std::vector<double>> v = Values(value, visited);
  if (!v.ok()) return v.status();
  double mean = 0;
  for (double x : *v) mean += x / static_cast<double>(v->size());
  if (!(std::abs(mean) > 1e-12)) return absl::FailedPreconditionError("curriculum: the mean value mu is 0; (V - mu) / mu is undefined");
  return mean;
}

std::vector<std::vector<double>> ParameterCurriculum::ChainStarts(int count) {
  std::vector<std::vector<double>> starts;
  std::uniform_int_distribution<int64_t> pick(0, density_.size() - 1);
  for (int t = 0; t < 50 * count && static_cast<int>(starts.size()) < count; ++t) {
    const std::vector<double>& a = density_.point(pick(rng_));
    if (density_.Evaluate(a) >= config_.refine_density_min) starts.push_back(a);
  }
  // Few found: chains share starts (they diverge within a few steps); none: empty.
  for (size_t i = 0; !starts.empty() && static_cast<int>(starts.size()) < count; ++i) starts.push_back(starts[i]);
  return starts;
}

absl::StatusOr<CurriculumBatch> ParameterCurriculum::SampleRefinement(int count, const ValueFunction& value) {
  if (density_.size() == 0) return absl::FailedPreconditionError("curriculum: no parameters visited yet");
  CurriculumBatch batch;
  batch.mode = CurriculumMode::kRefinement;
  batch.episodes_per_param = config_.episodes_per_param;
  std::vector<std::vector<double>> chains = ChainStarts(count);
  if (chains.empty()) return batch;  // no heavily visited region
  absl::StatusOr<double> mu = MeanVisitedValue(value);
  if (!mu.ok()) return mu.status();
  absl::StatusOr<std::vector<double>> v = Values(value, chains);
  if (!v.ok()) return v.status();
  std::normal_distribution<double> step(0.0, config_.mcmc_step);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int s = 0; s < config_.mcmc_steps; ++s) {
    // Metropolis: a symmetric random walk; a proposal outside [0, 1] or the heavily visited
    // region has target 0 and is rejected.
    std::vector<std::vector<double>> proposals;
    std::vector<int> chain_of;
    for (int c = 0; c < count; ++c) {
      std::vector<double> a = chains[c];
      bool inside = true;
      for (size_t i = 0; i < a.size(); ++i) {
        if (!free_[i]) continue;
        a[i] += step(rng_);
        inside = inside && a[i] >= 0 && a[i] <= 1;
      }
      if (inside && density_.Evaluate(a) >= config_.refine_density_min) {
        proposals.push_back(std::move(a));
        chain_of.push_back(c);
      }
    }
    if (proposals.empty()) continue;
    absl::StatusOr<std::vector<double>> pv = Values(value, proposals);
    if (!pv.ok()) return pv.status();
    for (size_t p = 0; p < proposals.size(); ++p) {
      const int c = chain_of[p];
      // p(a') / p(a) = exp(-k (V(a') - V(a)) / |mu|)
      const double log_ratio = -config_.value_k * ((*pv)[p] - (*v)[c]) / std::abs(*mu);
      if (log_ratio >= 0 || unit(rng_) < std::exp(log_ratio)) {
        chains[c] = std::move(proposals[p]);
        (*v)[c] = (*pv)[p];
      }
    }
  }
  batch.params = std::move(chains);
  return batch;
}

absl::StatusOr<CurriculumBatch> ParameterCurriculum::NextBatch(const ValueFunction& value) {
  if (density_.size() == 0) {
    return absl::FailedPreconditionError("curriculum: no parameters visited yet (add the clip's own parameters first)");
  }
  if (mode_ == CurriculumMode::kRefinement) {
    absl::StatusOr<CurriculumBatch> batch = SampleRefinement(config_.params_per_batch, value);
    if (!batch.ok() || !batch->params.empty()) return batch;
  }
  return SampleExploration(config_.params_per_batch);
}

absl::Status ParameterCurriculum::ReportBatch(CurriculumMode batch_mode, int new_elites, int episodes) {
  if (episodes < 1 || new_elites < 0 || new_elites > episodes) {
    return absl::InvalidArgumentError(
        absl::StrCat("curriculum: batch report of ", new_elites, " new elites in ", episodes, " episodes"));
  }
  if (batch_mode == CurriculumMode::kExploration) exploration_rate_ = static_cast<double>(new_elites) / episodes;
  if (mode_ == CurriculumMode::kExploration) {
    if (exploration_rate_ < config_.min_exploration_rate) {
      mode_ = CurriculumMode::kRefinement;
      refinement_left_ = config_.refinement_batches;
    }
  } else if (--refinement_left_ <= 0) {
    mode_ = CurriculumMode::kExploration;
  }
  return absl::OkStatus();
}

}  // namespace modskill::learner::family
