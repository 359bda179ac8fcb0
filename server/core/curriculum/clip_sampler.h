// Which clip an env starts from: a weighted draw. Weights change between steps (adaptive
// sampling), never during one.
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_CLIP_SAMPLER_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_CLIP_SAMPLER_H_

#include <random>
#include <vector>

#include "absl/status/status.h"
#include "absl/types/span.h"

namespace modskill {

class ClipSampler {
 public:
  explicit ClipSampler(int num_clips);

  // Weights must be finite, >= 0, with a positive sum; one per clip.
  absl::Status SetWeights(absl::Span<const double> weights);
  const std::vector<double>& weights() const { return weights_; }
  int num_clips() const { return static_cast<int>(weights_.size()); }
  double Probability(int clip) const { return weights_[clip] / cumulative_.back(); }

  // Allocation free.
  int Sample(std::mt19937_64& rng) const;

 private:
  std::vector<double> weights_;
  std::vector<double> cumulative_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_CLIP_SAMPLER_H_
