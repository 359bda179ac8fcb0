// The curriculum over task parameters (Lee et al. 2021; DESIGN.md section 4). Each batch picks
// 20 parameter vectors, each run for 30 episodes, in one of two modes. Our reading of the rule:
// - Exploration pushes the frontier: it samples uniformly and keeps a vector only where the
//   visit density (parameter_density.h) is in [0.2, 0.8], the edge of the visited region:
//   unvisited space (~0) is too far from what the policy can do, covered space (~1) is known.
// - Refinement improves the policy where it has been: MCMC (Metropolis, Gaussian random walk)
//   over the heavily visited region (density >= 0.8) with target
//     p(a) ~ exp(-k (V(a) - mu) / |mu|),  k = 10,
//   V the value estimate for parameters a and mu its mean over visited parameters, so vectors
//   whose value is below the mean (where the policy is still weak) are drawn e^{k x} times
//   more often, x their relative shortfall. (|mu|: the paper's mu is a positive return; the
//   absolute value keeps "lower V, more samples" should a critic's mean turn negative.)
// - The switch, on the exploration rate: the share of a batch's episodes whose motion entered
//   the elite set. Exploration continues while its last batch's rate is >= min_exploration_rate
//   (the frontier still yields elites); below it, `refinement_batches` refinement batches run,
//   then exploration again. A refinement batch with no heavily visited region explores.
// Deterministic for a seed (std::mt19937_64).
#ifndef MODSKILL_LEARNER_FAMILY_PARAMETER_CURRICULUM_H_
#define MODSKILL_LEARNER_FAMILY_PARAMETER_CURRICULUM_H_

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "common/policy/family_parameters.h"
#include "learner/family/parameter_density.h"

namespace modskill::learner::family {

enum class CurriculumMode { kExploration, kRefinement };

struct CurriculumConfig {
  int params_per_batch = 20;     // the paper's batch: 20 parameters x 30 episodes
  int episodes_per_param = 30;
  double explore_density_lo = 0.2;
  double explore_density_hi = 0.8;
  double refine_density_min = 0.8;  // "heavily visited"
  double value_k = 10;              // k
  double min_exploration_rate = 0.05;
  int refinement_batches = 1;
  int explore_tries = 2000;         // uniform draws per vector before the fallback
  int mcmc_steps = 100;             // Metropolis steps per chain (one chain per vector)
  double mcmc_step = 0.1;           // random-walk sigma, normalized units
  int value_mean_samples = 1024;    // visited vectors mu is averaged over (all when fewer)
  DensityConfig density;
};

// Normalized parameter vectors in, their value estimates V(a) out (one batched critic call).
using ValueFunction = std::function<std::vector<double>(const std::vector<std::vector<double>>&)>;

struct CurriculumBatch {
  CurriculumMode mode = CurriculumMode::kExploration;
  std::vector<std::vector<double>> params;  // normalized; constraint dimensions are 0
  int episodes_per_param = 0;
  // Exploration: how many vectors lay in the density band; the rest are the draws nearest it
  // (early on, with few visits, the band can be empty).
  int in_band = 0;
};

class ParameterCurriculum {
 public:
  // INVALID_ARGUMENT for a config out of range (batch sizes < 1, a density band not within
  // [0, 1] or inverted, k <= 0, ...), naming the field.
  static absl::StatusOr<ParameterCurriculum> Create(const ParamSpace& space, CurriculumConfig config, uint64_t seed);

  // A parameter vector an episode ran with (normalized).
  absl::Status AddVisited(absl::Span<const double> params) { return density_.Add(params); }
  // The next batch in the current mode. INVALID_ARGUMENT when `value` returns the wrong count
  // or a non-finite value; FAILED_PRECONDITION when nothing was visited yet (seed the density
  // with the clip's own parameters) or the mean value is 0.
  absl::StatusOr<CurriculumBatch> NextBatch(const ValueFunction& value);
  // How a batch went: `new_elites` of its `episodes` entered the elite set. An exploration
  // batch sets the exploration rate; the rate and the refinement count set the next mode.
  // INVALID_ARGUMENT for episodes < 1 or new_elites outside [0, episodes].
  absl::Status ReportBatch(CurriculumMode batch_mode, int new_elites, int episodes);

  CurriculumMode mode() const { return mode_; }
  double exploration_rate() const { return exploration_rate_; }
  const ParameterDensity& density() const { return density_; }

  // The two samplers, public for tests and benchmarks. SampleRefinement returns an empty
  // batch when no visited vector lies in a heavily visited region.
  CurriculumBatch SampleExploration(int count);
  absl::StatusOr<CurriculumBatch> SampleRefinement(int count, const ValueFunction& value);

 private:
  ParameterCurriculum(std::vector<bool> free, CurriculumConfig config, uint64_t seed);
  std::vector<double> UniformDraw();
  absl::StatusOr<std::vector<double>> Values(const ValueFunction& value, const std::vector<std::vector<double>>& params) const;
  absl::StatusOr<double> MeanVisitedValue(const ValueFunction& value);
  std::vector<std::vector<double>> ChainStarts(int count);

  std::vector<bool> free_;  // false for a constraint dimension (zero-width range)
  CurriculumConfig config_;
  std::mt19937_64 rng_;
  ParameterDensity density_;
  CurriculumMode mode_ = CurriculumMode::kExploration;
  int refinement_left_ = 0;
  double exploration_rate_ = 1;
};

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_PARAMETER_CURRICULUM_H_
