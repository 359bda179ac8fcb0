// Active skill learning's clip sampler (docs/DESIGN.md section 3): clips the learner fails on are
// drawn more often. Two schemes from the literature, a length-fair one, and the uniform ablation:
//   kFailureCount (PHC): probability ∝ a clip's recent failures. "Recent" is an exponential
//     moving count, so that a clip that is learned drifts back: count += 1 per failure,
//     count *= kFailureCountSuccessDecay (0.9) per success; weight = count + kFailureCountEpsilon.
//   kDecayOnSuccess (ProtoMotions): weight *= decay (0.999) per success, weight = 1 per failure
//     (every weight starts at 1).
//   kFailureRate: probability ∝ failures per simulated control step (a hazard rate). Episodes
//     start at random frames and succeed only at a clip's end, so under kFailureCount a long
//     clip fails most of its episodes however well it is tracked (a 23-s clip took 20-31 % of
//     the draws among 20 in our runs); per step, a clip is as hard as how soon it is lost.
//     Moving sums F (failures) and S (steps, ClipFailure.steps) decay by kFailureRateMemory per
//     report on the clip; weight = (F + kFailureRatePriorFailures) / (S + kFailureRatePriorSteps).
//   kUniform: never moves (the --no_adaptive ablation).
// Probabilities are proportional to the weights, so a clip's successes lower its probability
// relative to the other clips' weights: a clip that is the only one failing keeps all the mass
// above the floor until its count decays to the order of ε (a few dozen successes).
// The raw weights are then turned into probabilities with a floor (see Weights()). Pure
// bookkeeping: knows nothing of envs, threads or gRPC; the owner decides when the result reaches
// the ClipSampler that envs draw from.
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_ADAPTIVE_SAMPLER_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_ADAPTIVE_SAMPLER_H_

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

enum class SamplingScheme {
  kUniform,
  kFailureCount,    // PHC
  kDecayOnSuccess,  // ProtoMotions
  kFailureRate,     // failures per step
};

// "uniform", "failure_count", "decay_on_success", "failure_rate"; anything else is
// INVALID_ARGUMENT naming the value.
absl::StatusOr<SamplingScheme> ParseSamplingScheme(absl::string_view name);
const char* SamplingSchemeName(SamplingScheme scheme);

// The floor the server uses unless told otherwise (--sampling_floor): every clip keeps at least
// 0.2 / N of the probability, so 80 % of the mass follows the failures and a fifth stays uniform.
inline constexpr double kDefaultSamplingFloor = 0.2;
inline constexpr double kDefaultSamplingDecay = 0.999;
// kFailureCount: per-success decay of the moving failure count, and the weight of a clip that
// never failed (relative to one fresh failure).
inline constexpr double kFailureCountSuccessDecay = 0.9;
inline constexpr double kFailureCountEpsilon = 1e-3;
// kFailureRate: the per-report decay of the moving sums (a memory of ~100 reports per clip), and
// the prior a clip starts from: one failure in 30 steps (a second), about what an untrained
// policy does, so that a clip not yet reported is neither ignored nor favoured.
inline constexpr double kFailureRateMemory = 0.99;
inline constexpr double kFailureRatePriorFailures = 1.0;
inline constexpr double kFailureRatePriorSteps = 30.0;

// Checks floor_fraction in [0, 1] and decay in (0, 1]; the message names `floor_field` or
// `decay_field`.
absl::Status ValidateSamplingParameters(double floor_fraction, double decay,
                                        absl::string_view floor_field = "sampling_floor",
                                        absl::string_view decay_field = "sampling_decay");

class AdaptiveSampler {
 public:
  // floor_fraction: the share of the probability mass spread uniformly as a floor, i.e. each
  // clip keeps >= floor_fraction / N (0: no floor; 1: uniform whatever the reports). Values
  // outside [0, 1] are clamped, a decay outside (0, 1] becomes 1; validate with
  // ValidateSamplingParameters first to report them.
  AdaptiveSampler(int num_clips, SamplingScheme scheme, double floor_fraction = kDefaultSamplingFloor,
                  double decay = kDefaultSamplingDecay);

  // One report: the clip's episode failed (terminated) or was tracked to its end after `steps`
  // control steps. `clip` must be in [0, num_clips) (the caller has validated it); others are
  // ignored. steps <= 0 is unknown: kFailureRate counts the clip's recent mean episode length.
  void Observe(int clip, bool failed, int steps = 0);

  // The clip list changed (generative resampling): new clip c was old clip previous[c] and keeps
  // its count and weight, or is new (-1) and starts as a never-failed clip would, except that
  // `new_clip_count` failures are credited to it (kFailureCount; kDecayOnSuccess: weight 1;
  // kFailureRate: the prior), so that a variant of a failing clip is drawn about as often as
  // its parent from the start.
  void Remap(const std::vector<int>& previous, double new_clip_count = 0.0);

  // Normalized probabilities with the floor applied (sum 1). With q_c = w_c / Σ w the scheme's
  // distribution and f = floor_fraction / N:
  //     p_c = max(f, λ q_c),   λ ∈ [0, 1] the unique value with Σ_c p_c = 1,
  // i.e. "clamp to the floor, renormalize the rest": clips below the floor get exactly f, the
  // others share the remaining mass 1 − k f in proportion to q_c (k = clips at the floor), so
  // the floor holds exactly after the renormalization and the order of the clips is kept.
  // Why a floor: without it a clip that is tracked well decays toward probability 0 and is never
  // seen again, so the policy can forget it unnoticed (its successes are no longer observed and
  // its weight can never recover); the floor keeps every clip in the training distribution.
  std::vector<double> Weights() const;

  // The scheme's raw weights w_c (failure count + ε, the decayed weight, or failures per step;
  // 1 for uniform).
  const std::vector<double>& raw_weights() const { return weights_; }
  SamplingScheme scheme() const { return scheme_; }
  double floor_fraction() const { return floor_fraction_; }
  int num_clips() const { return static_cast<int>(weights_.size()); }

 private:
  SamplingScheme scheme_;
  double floor_fraction_;
  double decay_;
  std::vector<double> counts_;   // kFailureCount, kFailureRate: moving failure counts
  std::vector<double> steps_;    // kFailureRate: moving step sums
  std::vector<double> reports_;  // kFailureRate: moving report counts (for unknown lengths)
  std::vector<double> weights_;  // raw weights
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_ADAPTIVE_SAMPLER_H_
