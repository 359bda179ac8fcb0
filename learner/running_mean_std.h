// Running mean and variance of the observations, used to normalize the networks' inputs.
#ifndef MODSKILL_LEARNER_RUNNING_MEAN_STD_H_
#define MODSKILL_LEARNER_RUNNING_MEAN_STD_H_

#include <cstdint>

#include <torch/torch.h>

namespace modskill::learner {

// Buffers (float64, not trained): mean [D], var [D] (population variance), count [] (samples
// seen). Starts at mean 0, var 1, count 0, so the first Update replaces them.
class RunningMeanStdImpl : public torch::nn::Module {
 public:
  explicit RunningMeanStdImpl(int64_t size);

  // The moments of some samples: their count, mean [D] and population variance [D], float64.
  struct Moments {
    double count = 0;
    torch::Tensor mean, var;
  };

  // batch: [B, D]. Merges the batch's mean and variance with the running ones by the parallel
  // algorithm of Chan, Golub, LeVeque (1979), in double precision. No gradient.
  void Update(const torch::Tensor& batch);
  // batch: [B, D], B > 0 -> its moments, computed in the batch's own precision.
  Moments BatchMoments(const torch::Tensor& batch) const;
  // Merges moments (of one batch, or several combined) into the running ones, as Update does.
  void Merge(const Moments& batch);
  // The moments of the union of the samples of `a` and `b` (Chan et al.); either may be empty.
  static Moments Combine(const Moments& a, const Moments& b);

  // Dims whose mean and var Update leaves as they are (mask: [D] bool), e.g. the self features of
  // a task policy, which its frozen skills must see normalized exactly as their tracker saw them.
  // Not saved with the module: whoever builds the normalizer sets it again (skill_library.h).
  void FreezeDims(const torch::Tensor& mask);
  const torch::Tensor& frozen() const { return frozen_; }  // undefined when none was set

  // x: [B, D] -> clamp((x - mean) / sqrt(var + 1e-5), -5, 5), in x's dtype: [B, D].
  torch::Tensor Normalize(const torch::Tensor& x) const;

  int64_t size() const { return size_; }
  const torch::Tensor& mean() const { return mean_; }
  const torch::Tensor& var() const { return var_; }
  const torch::Tensor& count() const { return count_; }

  static constexpr double kEpsilon = 1e-5;
  static constexpr double kClip = 5.0;

 private:
  int64_t size_;
  torch::Tensor mean_, var_, count_;
  torch::Tensor frozen_;
};
TORCH_MODULE(RunningMeanStd);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_RUNNING_MEAN_STD_H_
