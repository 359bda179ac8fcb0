// The PPO policy and value update over one iteration's batch (Schulman et al. 2017): epochs of
// shuffled minibatches, each a clipped-surrogate step of the policy (in its sample space,
// ModSkillPolicyImpl::SampleMean) and the critic. The trainer runs it; tests run it without a server.
#ifndef MODSKILL_LEARNER_PPO_UPDATE_H_
#define MODSKILL_LEARNER_PPO_UPDATE_H_

#include <cstdint>
#include <functional>
#include <vector>

#include <torch/torch.h>

#include "absl/status/statusor.h"

#include "learner/critic.h"
#include "learner/modskill_policy.h"

namespace modskill::learner {

struct PpoSettings {
  int epochs = 2;
  int64_t minibatch_size = 2048;
  double clip_ratio = 0.2, value_clip = 0.2, value_coefficient = 2.0, max_grad_norm = 1.0;
  // Data-parallel learners: minibatch steps per epoch, the same on every rank (-1: as many as the
  // batch holds).
  int64_t minibatches_per_epoch = -1;
  // [sample_size]: 1 where PPO samples, 0 where the policy acts on its mean (frozen parts, see
  // TrainerConfig::frozen_parts_act_on_mean); undefined: every dim is sampled.
  torch::Tensor sampled_dims;
  // Behaviour cloning of a reach teacher (reach_teacher.h): the loss adds teacher_weight × the
  // teacher loss of the head's mean z against PpoBatch::teacher_z over the parts marked 1 in
  // teacher_parts ([P]). 0: no teacher.
  double teacher_weight = 0;
  torch::Tensor teacher_parts;
};

// Data-parallel learners (data_parallel.h): called after every minibatch's backward pass (with
// `finite` false, and no backward, when the loss was not finite) to average the gradients of
// `params` across ranks. Returns whether to step: false when any rank's loss was not finite; an
// error when the ranks could not be reached.
using GradientAverager = std::function<absl::StatusOr<bool>(const std::vector<torch::Tensor>& params, bool finite)>;

// One iteration's experience, [N, ...]: normalized observations, the sampled PPO actions
// ([N, sample_size]), and the behaviour's log-probabilities, values, advantages and returns.
struct PpoBatch {
  torch::Tensor obs, samples, old_log_prob, old_values, advantages, returns;
  torch::Tensor teacher_z;  // [N, P, E] with PpoSettings::teacher_weight > 0
};

struct PpoUpdateStats {
  double policy_loss = 0, value_loss = 0, approx_kl = 0, clip_fraction = 0;  // means over the steps taken
  double teacher_loss = 0;  // unweighted, mean over the steps taken (0 without a teacher)
  int updates = 0;          // minibatch steps taken
  int skipped_updates = 0;  // minibatches skipped for a non-finite loss, plus 1 for a rollback
  bool rolled_back = false;  // non-finite weights after the update: the weights it started from are back
  absl::Status error;        // from the GradientAverager; the update stopped there
};

// What the optimizer trains: the parameters of `policy` that require gradients (not the frozen
// skills of a task policy), then the critic's.
std::vector<torch::Tensor> TrainableParameters(ModSkillPolicyImpl& policy, CriticImpl& critic);

// The same parameters as Adam's groups: one group at `learning_rate`, or with critic_learning_rate
// > 0 two, the policy's (group 0) and the critic's (group 1) at their own rates.
std::vector<torch::optim::OptimizerParamGroup> TrainableParameterGroups(ModSkillPolicyImpl& policy, CriticImpl& critic,
                                                                        double learning_rate,
                                                                        double critic_learning_rate);

// Minibatch steps per epoch over `size` samples: whole minibatches of min(minibatch_size, size).
int64_t MinibatchesPerEpoch(int64_t size, int64_t minibatch_size);

// Runs settings.epochs epochs over `batch` with `optimizer` (built on TrainableParameters or
// TrainableParameterGroups; gradients are clipped over all of its groups together),
// minibatch order from `generator`; `average` (optional) averages the gradients across ranks.
PpoUpdateStats UpdateWithPpo(ModSkillPolicyImpl& policy, CriticImpl& critic, torch::optim::Optimizer& optimizer,
                             const PpoBatch& batch, const PpoSettings& settings, torch::Generator& generator,
                             const GradientAverager& average = nullptr);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_PPO_UPDATE_H_
