// The policy and critic of a motor-skill family (Lee et al. 2021; DESIGN.md section 4): plain
// MLPs over the whole observation (tracking's features, then a normalized and the phase), since
// the family is one clip's motion and not a library of part skills. The action is the hinges'
// displacements plus the time warp tau (EnvSpec.time_warp_action), Gaussian with a learned,
// state-independent log standard deviation.
#ifndef MODSKILL_LEARNER_FAMILY_FAMILY_POLICY_H_
#define MODSKILL_LEARNER_FAMILY_FAMILY_POLICY_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "learner/running_mean_std.h"

namespace modskill::learner::family {

struct FamilyPolicyConfig {
  int64_t obs_size = 0;
  int64_t action_size = 0;
  // DESIGN.md: policy 4 x 1024, value 2 x 512; the defaults fit two CPU cores.
  std::vector<int64_t> policy_hidden = {512, 256};
  std::vector<int64_t> value_hidden = {256, 256};
  double initial_log_std = -1.6;  // std 0.2: a displacement starts small, tau near the clip's pace
};

class FamilyActorCriticImpl : public torch::nn::Module {
 public:
  explicit FamilyActorCriticImpl(const FamilyPolicyConfig& config);

  // obs [B, obs_size] (raw; normalized here) -> action means [B, action_size].
  torch::Tensor Mean(const torch::Tensor& obs);
  // obs [B, obs_size] -> V [B].
  torch::Tensor Value(const torch::Tensor& obs);
  // Log-density of actions [B, A] under N(mean, exp(log_std)) -> [B]; the entropy [B].
  torch::Tensor LogProb(const torch::Tensor& mean, const torch::Tensor& actions) const;
  torch::Tensor Entropy(int64_t batch) const;

  RunningMeanStd& obs_norm() { return obs_norm_; }
  const torch::Tensor& log_std() const { return log_std_; }
  const FamilyPolicyConfig& config() const { return config_; }
  const torch::nn::Sequential& policy_mlp() const { return policy_; }  // normalized obs -> means

 private:
  FamilyPolicyConfig config_;
  RunningMeanStd obs_norm_{nullptr};
  torch::nn::Sequential policy_{nullptr}, value_{nullptr};
  torch::Tensor log_std_;
};
TORCH_MODULE(FamilyActorCritic);

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_FAMILY_POLICY_H_
