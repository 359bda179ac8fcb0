// The elite set (Lee et al. 2021; DESIGN.md section 4): per region of the parameter space, the
// fittest motion found so far, as the trajectory {(d_t, tau_t)} the episode played. Its elites
// are the parameterization network's training data and its bootstrap.
// Replacement rule (our reading of "a new episode replaces neighbours within r if fitter"): an
// episode at a enters when it is fitter than every elite within r of a; those elites leave. If
// any of them is at least as fit, the episode is dropped. With none within r it enters.
#ifndef MODSKILL_LEARNER_FAMILY_ELITE_SET_H_
#define MODSKILL_LEARNER_FAMILY_ELITE_SET_H_

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "learner/family/kd_tree.h"

namespace modskill::learner::family {

struct EliteSetConfig {
  double replace_radius = 0.1;  // r, in normalized parameter units
};

struct Elite {
  std::vector<double> params;  // a, normalized to [0, 1] per dimension (common/policy/family_parameters.h)
  double fitness = 0;          // F (common/policy/family_fitness.h)
  torch::Tensor trajectory;    // [L, D]: (d_t, tau_t) at each of the clip's L frames
};

class EliteSet {
 public:
  // dims: the parameter space's; every elite's trajectory is [frames, outputs].
  EliteSet(int dims, int64_t frames, int64_t outputs, EliteSetConfig config = {});

  // Offers an episode; true when it entered. INVALID_ARGUMENT for parameters of the wrong size
  // or outside [0, 1], a non-finite fitness, or a trajectory that is not a finite [L, D].
  absl::StatusOr<bool> Offer(absl::Span<const double> params, double fitness, const torch::Tensor& trajectory);

  int dims() const { return tree_.dims(); }
  int64_t frames() const { return frames_; }
  int64_t outputs() const { return outputs_; }
  int64_t size() const { return tree_.size(); }
  // The min(k, size()) elites nearest `params`, nearest first (ids for elite()).
  std::vector<Neighbor> Nearest(absl::Span<const double> params, int k) const { return tree_.Nearest(params, k); }
  const Elite& elite(int64_t id) const { return elites_.at(id); }
  // Ids of every elite, in no particular order.
  std::vector<int64_t> Ids() const;

 private:
  absl::Status CheckOffer(absl::Span<const double> params, double fitness, const torch::Tensor& trajectory) const;

  int64_t frames_, outputs_;
  EliteSetConfig config_;
  KdTree tree_;
  std::vector<Elite> elites_;      // by id; a removed elite's slot is reused
  std::vector<int64_t> free_ids_;
};

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_ELITE_SET_H_
