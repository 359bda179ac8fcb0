#include "learner/ppo_update.h"

#include <algorithm>
#include <cmath>

#include "learner/ppo_loss.h"
#include "learner/reach_teacher.h"

namespace modskill::learner {
namespace {

bool AllFinite(const std::vector<torch::Tensor>& tensors) {
  for (const torch::Tensor& t : tensors) {
    if (!torch::isfinite(t).all().item<bool>()) return false;
  }
  return true;
}

}  // namespace

namespace {

// The policy's parameters that require gradients: not the frozen skills of a task policy.
std::vector<torch::Tensor> TrainablePolicyParameters(ModSkillPolicyImpl& policy) {
  std::vector<torch::Tensor> parameters;
  for (const torch::Tensor& p : policy.parameters()) {
    if (p.requires_grad()) parameters.push_back(p);
  }
  return parameters;
}

}  // namespace

std::vector<torch::Tensor> TrainableParameters(ModSkillPolicyImpl& policy, CriticImpl& critic) {
  std::vector<torch::Tensor> parameters = TrainablePolicyParameters(policy);
  for (const torch::Tensor& p : critic.parameters()) parameters.push_back(p);
  return parameters;
}

std::vector<torch::optim::OptimizerParamGroup> TrainableParameterGroups(ModSkillPolicyImpl& policy, CriticImpl& critic,
                                                                        double learning_rate,
                                                                        double critic_learning_rate) {
  const auto group = [](std::vector<torch::Tensor> params, double rate) {
    return torch::optim::OptimizerParamGroup(std::move(params), std::make_unique<torch::optim::AdamOptions>(rate));
  };
  std::vector<torch::optim::OptimizerParamGroup> groups;
  if (critic_learning_rate <= 0) {
    groups.push_back(group(TrainableParameters(policy, critic), learning_rate));
    return groups;
  }
  groups.push_back(group(TrainablePolicyParameters(policy), learning_rate));
  groups.push_back(group(critic.parameters(), critic_learning_rate));
  return groups;
}

int64_t MinibatchesPerEpoch(int64_t size, int64_t minibatch_size) {
  return size == 0 ? 0 : size / std::min<int64_t>(minibatch_size, size);
}

// A non-finite loss skips its minibatch (on every rank); non-finite weights after the update roll
// back to the weights it started from.
PpoUpdateStats UpdateWithPpo(ModSkillPolicyImpl& policy, CriticImpl& critic, torch::optim::Optimizer& optimizer,
                             const PpoBatch& batch, const PpoSettings& settings, torch::Generator& generator,
                             const GradientAverager& average) {
  PpoUpdateStats stats;
  std::vector<torch::Tensor> params;
  for (const torch::optim::OptimizerParamGroup& group : optimizer.param_groups()) {
    params.insert(params.end(), group.params().begin(), group.params().end());
  }
  std::vector<torch::Tensor> snapshot;
  for (const torch::Tensor& p : params) snapshot.push_back(p.detach().clone());
  const torch::Tensor log_std = policy.log_std();
  const int64_t size = batch.obs.size(0);
  const int64_t minibatch = std::min<int64_t>(settings.minibatch_size, size);
  const int64_t steps = settings.minibatches_per_epoch >= 0 ? settings.minibatches_per_epoch
                                                            : MinibatchesPerEpoch(size, settings.minibatch_size);
  for (int epoch = 0; epoch < settings.epochs && stats.error.ok(); ++epoch) {
    const torch::Tensor order = torch::randperm(size, generator);
    for (int64_t step = 0; step < steps; ++step) {
      const torch::Tensor index = order.slice(0, step * minibatch, (step + 1) * minibatch);
      const torch::Tensor obs = batch.obs.index_select(0, index);
      const torch::Tensor mean = policy.SampleMean(obs);
      const torch::Tensor new_log_prob =
          ModSkillPolicyImpl::LogProb(mean, log_std, batch.samples.index_select(0, index), settings.sampled_dims);
      PpoLossTerms loss = ComputePpoLoss(new_log_prob, batch.old_log_prob.index_select(0, index),
                                         batch.advantages.index_select(0, index), critic.NormalizedValue(obs),
                                         batch.old_values.index_select(0, index), batch.returns.index_select(0, index),
                                         settings.clip_ratio, settings.value_clip, settings.value_coefficient);
      torch::Tensor teacher_loss;
      if (settings.teacher_weight > 0) {
        teacher_loss = TeacherLoss(policy.TaskZ(obs, mean), batch.teacher_z.index_select(0, index), settings.teacher_parts);
        loss.total = loss.total + settings.teacher_weight * teacher_loss;
      }
      const bool finite = std::isfinite(loss.total.item<double>());
      if (!finite && !average) {
        ++stats.skipped_updates;
        continue;
      }
      optimizer.zero_grad();
      if (finite) loss.total.backward();
      if (average) {
        // Every rank takes this step or none does, with the same averaged gradients.
        const absl::StatusOr<bool> all_finite = average(params, finite);
        if (!all_finite.ok()) {
          stats.error = all_finite.status();
          break;
        }
        if (!*all_finite) {
          ++stats.skipped_updates;
          continue;
        }
      }
      torch::nn::utils::clip_grad_norm_(params, settings.max_grad_norm);
      optimizer.step();
      stats.policy_loss += loss.policy_loss.item<double>();
      stats.value_loss += loss.value_loss.item<double>();
      stats.approx_kl += loss.approx_kl.item<double>();
      stats.clip_fraction += loss.clip_fraction.item<double>();
      if (teacher_loss.defined()) stats.teacher_loss += teacher_loss.item<double>();
      ++stats.updates;
    }
  }
  if (!AllFinite(params)) {
    torch::NoGradGuard no_grad;
    for (size_t i = 0; i < params.size(); ++i) params[i].copy_(snapshot[i]);
    stats.rolled_back = true;
    ++stats.skipped_updates;
  }
  if (stats.updates > 0) {
    stats.policy_loss /= stats.updates;
    stats.value_loss /= stats.updates;
    stats.approx_kl /= stats.updates;
    stats.clip_fraction /= stats.updates;
    stats.teacher_loss /= stats.updates;
  }
  return stats;
}

}  // namespace modskill::learner
