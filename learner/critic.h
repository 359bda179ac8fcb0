// The value function V(s): an ELU MLP from the normalized observation to one value.
//
// With return normalization on (rl_games' normalize_value, which AMP, ASE and PHC train with) the
// MLP predicts returns in units of the running return statistics, so the value loss, its clip
// range and its share of the clipped gradient norm keep one scale while returns grow from a few
// to tens of rewards; forward() still gives values in reward units for GAE.
#ifndef MODSKILL_LEARNER_CRITIC_H_
#define MODSKILL_LEARNER_CRITIC_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "learner/part_controller.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

class CriticImpl : public torch::nn::Module {
 public:
  CriticImpl(int64_t obs_size, const std::vector<int64_t>& hidden, bool normalize_returns = false);

  // normalized_obs: [B, obs_size] -> value in reward units: [B]
  torch::Tensor forward(const torch::Tensor& normalized_obs);
  // The MLP's own output, in normalized return units when normalizes_returns(): [B]. The value
  // loss compares it with NormalizeReturns of the targets.
  torch::Tensor NormalizedValue(const torch::Tensor& normalized_obs);
  // returns: [B] in reward units -> (returns - mean) / std of the running statistics; the
  // identity without return normalization.
  torch::Tensor NormalizeReturns(const torch::Tensor& returns) const;

  bool normalizes_returns() const { return normalize_returns_.item<int64_t>() != 0; }
  // The running return statistics ([1] wide); the trainer updates them once per iteration.
  RunningMeanStdImpl& return_statistics() { return *return_norm_; }

  // Loads a critic saved before return normalization existed (no "return_norm", no
  // "normalize_returns": it predicted raw returns) as one that does not normalize.
  void load(torch::serialize::InputArchive& archive) override;

 private:
  Mlp mlp_;
  RunningMeanStd return_norm_;
  torch::Tensor normalize_returns_;  // int64 scalar buffer, so checkpoints and snapshots carry the mode
};
TORCH_MODULE(Critic);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_CRITIC_H_
