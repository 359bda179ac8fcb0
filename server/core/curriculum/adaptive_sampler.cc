#include "server/core/curriculum/adaptive_sampler.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

// The raw weight of a clip with no reports.
double FreshWeight(SamplingScheme scheme) {
  switch (scheme) {
    case SamplingScheme::kFailureCount:
      return kFailureCountEpsilon;
    case SamplingScheme::kFailureRate:
      return kFailureRatePriorFailures / kFailureRatePriorSteps;
    case SamplingScheme::kUniform:
    case SamplingScheme::kDecayOnSuccess:
      return 1.0;
  }
  return 1.0;
}

}  // namespace

absl::StatusOr<SamplingScheme> ParseSamplingScheme(absl::string_view name) {
  if (name == "uniform") return SamplingScheme::kUniform;
  if (name == "failure_count") return SamplingScheme::kFailureCount;
  if (name == "decay_on_success") return SamplingScheme::kDecayOnSuccess;
  if (name == "failure_rate") return SamplingScheme::kFailureRate;
  return absl::InvalidArgumentError(
      absl::StrCat("sampling: '", name, "' is not one of uniform, failure_count, decay_on_success, failure_rate"));
}

const char* SamplingSchemeName(SamplingScheme scheme) {
  switch (scheme) {
    case SamplingScheme::kUniform:
      return "uniform";
    case SamplingScheme::kFailureCount:
      return "failure_count";
    case SamplingScheme::kDecayOnSuccess:
      return "decay_on_success";
    case SamplingScheme::kFailureRate:
      return "failure_rate";
  }
  return "unknown";
}

absl::Status ValidateSamplingParameters(double floor_fraction, double decay, absl::string_view floor_field,
                                        absl::string_view decay_field) {
  if (!std::isfinite(floor_fraction) || floor_fraction < 0 || floor_fraction > 1) {
    return absl::InvalidArgumentError(absl::StrCat(floor_field, ": ", floor_fraction, " outside [0, 1]"));
  }
  if (!std::isfinite(decay) || decay <= 0 || decay > 1) {
    return absl::InvalidArgumentError(absl::StrCat(decay_field, ": ", decay, " outside (0, 1]"));
  }
  return absl::OkStatus();
}

AdaptiveSampler::AdaptiveSampler(int num_clips, SamplingScheme scheme, double floor_fraction, double decay)
    : scheme_(scheme),
      floor_fraction_(std::isfinite(floor_fraction) ? std::clamp(floor_fraction, 0.0, 1.0) : 1.0),
      decay_(std::isfinite(decay) && decay > 0 && decay <= 1 ? decay : 1.0),
      counts_(std::max(num_clips, 0), 0.0),
      steps_(std::max(num_clips, 0), 0.0),
      reports_(std::max(num_clips, 0), 0.0),
      weights_(std::max(num_clips, 0), FreshWeight(scheme)) {}

void AdaptiveSampler::Observe(int clip, bool failed, int steps) {
  if (clip < 0 || clip >= num_clips()) return;
  switch (scheme_) {
    case SamplingScheme::kUniform:
      return;
    case SamplingScheme::kFailureCount:
      counts_[clip] = failed ? counts_[clip] + 1.0 : counts_[clip] * kFailureCountSuccessDecay;
      weights_[clip] = counts_[clip] + kFailureCountEpsilon;
      return;
    case SamplingScheme::kDecayOnSuccess:
      weights_[clip] = failed ? 1.0 : weights_[clip] * decay_;
      return;
    case SamplingScheme::kFailureRate: {
      const double length = steps > 0                ? static_cast<double>(steps)
                            : reports_[clip] > 0     ? steps_[clip] / reports_[clip]
                                                     : kFailureRatePriorSteps;
      counts_[clip] = kFailureRateMemory * counts_[clip] + (failed ? 1.0 : 0.0);
      steps_[clip] = kFailureRateMemory * steps_[clip] + length;
      reports_[clip] = kFailureRateMemory * reports_[clip] + 1.0;
      weights_[clip] = (counts_[clip] + kFailureRatePriorFailures) / (steps_[clip] + kFailureRatePriorSteps);
      return;
    }
  }
}

void AdaptiveSampler::Remap(const std::vector<int>& previous, double new_clip_count) {
  const double fresh_count = std::isfinite(new_clip_count) ? std::max(new_clip_count, 0.0) : 0.0;
  const size_t n = previous.size();
  std::vector<double> counts(n, 0.0), steps(n, 0.0), reports(n, 0.0), weights(n, FreshWeight(scheme_));
  for (size_t c = 0; c < n; ++c) {
    const int old = previous[c];
    if (old >= 0 && old < num_clips()) {
      counts[c] = counts_[old];
      steps[c] = steps_[old];
      reports[c] = reports_[old];
      weights[c] = weights_[old];
    } else if (scheme_ == SamplingScheme::kFailureCount) {
      counts[c] = fresh_count;
      weights[c] = fresh_count + kFailureCountEpsilon;
    }
  }
  counts_ = std::move(counts);
  steps_ = std::move(steps);
  reports_ = std::move(reports);
  weights_ = std::move(weights);
}

std::vector<double> AdaptiveSampler::Weights() const {
  const int n = num_clips();
  std::vector<double> p(n, n > 0 ? 1.0 / n : 0.0);
  if (n <= 1 || scheme_ == SamplingScheme::kUniform) return p;
  // q: the scheme's own distribution (uniform if every weight has decayed to nothing).
  const double total = std::accumulate(weights_.begin(), weights_.end(), 0.0);
  if (!(total > 0) || !std::isfinite(total)) return p;
  std::vector<double> q(n);
  for (int c = 0; c < n; ++c) q[c] = weights_[c] / total;
  const double floor = floor_fraction_ / n;
  // Water filling: with the clips sorted by q ascending, the k smallest sit at the floor and the
  // rest get λ q_c with λ = (1 − k f) / Σ_{rest} q. The smallest k for which the smallest of
  // the rest stays above the floor is the solution of p_c = max(f, λ q_c), Σ p = 1
  // (k = n − 1 always qualifies because n f <= 1; it is also the fallback against rounding).
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return q[a] < q[b]; });
  std::vector<double> rest(n + 1, 0.0);  // rest[k] = Σ_{i >= k} q[order[i]]
  for (int i = n - 1; i >= 0; --i) rest[i] = rest[i + 1] + q[order[i]];
  int k = n - 1;
  for (int j = 0; j < n - 1; ++j) {
    if (rest[j] > 0 && (1.0 - j * floor) / rest[j] * q[order[j]] >= floor) {
      k = j;
      break;
    }
  }
  const double lambda = rest[k] > 0 ? (1.0 - k * floor) / rest[k] : 0.0;
  for (int i = 0; i < n; ++i) p[order[i]] = i < k ? floor : std::max(floor, lambda * q[order[i]]);
  return p;
}

}  // namespace modskill
