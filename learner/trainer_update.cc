// The update phases: GAE returns, the PPO policy and value update, the AMP discriminator update.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/log.h"
#include "learner/amp_loss.h"
#include "learner/gae.h"
#include "learner/learning_rate_decay.h"
#include "learner/ppo_loss.h"
#include "learner/ppo_update.h"
#include "learner/trainer.h"
#include "learner/trainer_phases.h"
#include "learner/wire_torch.h"

namespace modskill::learner {

Trainer::TrainingBatch Trainer::ComputeReturns(const std::vector<SlotRollout*>& usable) {
  torch::NoGradGuard no_grad;
  const int T = config_.horizon;
  const int64_t O = layout_.obs_size, S = policy_->sample_size(), M = layout_.amp_obs_size;
  TrainingBatch batch;
  batch.terms_sum = torch::zeros({spec_.reward_terms_size()}, torch::kFloat64);
  std::vector<torch::Tensor> obs, actions, log_prob, values, advantages, returns, raw_obs, amp_rows, live_rows;
  for (SlotRollout* r : usable) {
    // Reward: the server's task reward (imitation + energy) and the AMP style reward.
    const torch::Tensor amp_flat = r->amp_next.reshape({-1, M});
    const torch::Tensor amp_reward =
        AmpReward(discriminator_->forward(amp_norm_->Normalize(amp_flat))).reshape({T, r->n}) * (1 - r->dones);
    const torch::Tensor last_values = critic_->forward(obs_norm_->Normalize(r->next_obs));
    // Time-outs bootstrap from the value of the state they ended in (rl_games' trick: the
    // row's next observation already belongs to the next episode).
    const torch::Tensor rewards = config_.task_reward_weight * r->task_reward +
                                  config_.amp_reward_weight * amp_reward + config_.gamma * r->values * r->truncated;
    torch::Tensor slot_advantages, slot_returns;
    ComputeGae(rewards, r->values, r->dones, last_values, config_.gamma, config_.lambda, &slot_advantages,
               &slot_returns);
    obs.push_back(r->obs.reshape({-1, O}));
    actions.push_back(r->actions.reshape({-1, S}));
    log_prob.push_back(r->log_prob.reshape({-1}));
    values.push_back(r->values.reshape({-1}));
    advantages.push_back(slot_advantages.reshape({-1}));
    returns.push_back(slot_returns.reshape({-1}));
    amp_rows.push_back(amp_flat);
    live_rows.push_back((r->dones.reshape({-1}) < 0.5).nonzero().squeeze(1));
    raw_obs.insert(raw_obs.end(), r->raw_obs.begin(), r->raw_obs.end());
    batch.task_sum += r->task_reward.sum().item<double>();
    batch.amp_sum += amp_reward.sum().item<double>();
    batch.samples += static_cast<double>(T) * r->n;
    batch.terms_sum += r->reward_terms_sum;
  }
  batch.obs = torch::cat(obs);
  batch.actions = torch::cat(actions);
  batch.old_log_prob = torch::cat(log_prob);
  batch.old_values = torch::cat(values);
  batch.advantages = NormalizeAdvantages(torch::cat(advantages));
  batch.returns = torch::cat(returns);
  batch.policy_amp = SampleLiveAmp(amp_rows, live_rows);
  batch.raw_obs = torch::cat(raw_obs);
  batch.live_sessions = static_cast<int>(usable.size());
  return batch;
}

void Trainer::CenterOnCurrentPolicy(TrainingBatch* batch) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> proximal;
  const torch::Tensor log_std = policy_->log_std();
  const int64_t size = batch->obs.size(0), chunk = 4096;
  for (int64_t begin = 0; begin < size; begin += chunk) {
    const int64_t end = std::min(size, begin + chunk);
    proximal.push_back(ModSkillPolicyImpl::LogProb(policy_->SampleMean(batch->obs.slice(0, begin, end)), log_std,
                                                   batch->actions.slice(0, begin, end), sampled_dims_));
  }
  const torch::Tensor proximal_log_prob = torch::cat(proximal);
  batch->advantages = DecoupledAdvantages(batch->advantages, proximal_log_prob, batch->old_log_prob);
  batch->old_log_prob = proximal_log_prob;
}

torch::Tensor Trainer::SampleLiveAmp(const std::vector<torch::Tensor>& amp_rows,
                                    const std::vector<torch::Tensor>& live_rows) {
  int64_t live = 0;
  for (const torch::Tensor& rows : live_rows) live += rows.size(0);
  if (live == 0) return torch::zeros({0, layout_.amp_obs_size});
  const int64_t wanted = static_cast<int64_t>(config_.amp_samples) * config_.discriminator_epochs;
  const torch::Tensor pick = torch::randint(live, {wanted}, generator_, torch::kLong);
  std::vector<torch::Tensor> picked;
  int64_t offset = 0;
  for (size_t s = 0; s < amp_rows.size(); ++s) {
    const int64_t count = live_rows[s].size(0);
    const torch::Tensor mine = pick.masked_select((pick >= offset) & (pick < offset + count)) - offset;
    picked.push_back(amp_rows[s].index_select(0, live_rows[s].index_select(0, mine)));
    offset += count;
  }
  const torch::Tensor samples = torch::cat(picked);  // grouped by session: shuffle
  return samples.index_select(0, torch::randperm(samples.size(0), generator_));
}

// PPO (ppo_update.h). Iterate gives the update phases config.update_threads torch threads while
// the servers wait.
absl::Status Trainer::UpdatePolicy(const TrainingBatch& batch, IterationStats* stats) {
  // env_steps_ counts every rank's steps, so data-parallel ranks step alike.
  stats->learning_rate =
      LearningRateDecay{config_.learning_rate, config_.learning_rate_decay_steps, config_.learning_rate_floor}.RateAt(
          env_steps_);
  SetLearningRate(*optimizer_, stats->learning_rate);
  if (config_.critic_learning_rate > 0) {  // group 1, the critic's, decays by the same fraction
    stats->critic_learning_rate = config_.critic_learning_rate * stats->learning_rate / config_.learning_rate;
    static_cast<torch::optim::AdamOptions&>(optimizer_->param_groups()[1].options()).lr(stats->critic_learning_rate);
  }
  PpoSettings settings;
  settings.epochs = config_.epochs;
  settings.minibatch_size = config_.minibatch_size;
  settings.clip_ratio = config_.clip_ratio;
  settings.value_clip = config_.value_clip;
  settings.value_coefficient = config_.value_coefficient;
  settings.max_grad_norm = config_.max_grad_norm;
  settings.sampled_dims = sampled_dims_;
  torch::Tensor teacher_z;
  if (teacher_) {
    settings.teacher_weight = stats->teacher_weight =
        TeacherWeightAt(config_.task_teacher_weight, config_.task_teacher_steps, env_steps_);
    settings.teacher_parts = teacher_parts_;
    if (settings.teacher_weight > 0) {  // faded out: no pull, no lookup
      teacher_z = teacher_->NearestZ(batch.raw_obs.slice(1, layout_.goal_start, layout_.goal_start + layout_.goal_size));
    }
  }
  if (data_parallel_) {  // every rank steps as often as the smallest batch allows
    const absl::StatusOr<double> steps =
        data_parallel_->AllReduceMin(MinibatchesPerEpoch(batch.obs.size(0), config_.minibatch_size));
    if (!steps.ok()) return steps.status();
    settings.minibatches_per_epoch = static_cast<int64_t>(*steps);
  }
  // The critic learns returns in units of their running statistics, these returns included.
  if (critic_->normalizes_returns()) {
    if (absl::Status status = UpdateStats(critic_->return_statistics(), batch.returns.unsqueeze(1)); !status.ok()) {
      return status;
    }
  }
  const PpoBatch ppo{batch.obs, batch.actions, batch.old_log_prob, critic_->NormalizeReturns(batch.old_values),
                     batch.advantages, critic_->NormalizeReturns(batch.returns), teacher_z};
  const PpoUpdateStats update = UpdateWithPpo(*policy_, *critic_, *optimizer_, ppo, settings, generator_, Averager());
  if (!update.error.ok()) return update.error;
  stats->skipped_updates += update.skipped_updates;
  if (update.rolled_back) {
    LogLine("iteration %d: non-finite weights after the update; kept the last good ones", iteration_ + 1);
  }
  if (stats->skipped_updates > 0) {
    LogLine("iteration %d: skipped %d updates with a non-finite loss", iteration_ + 1, stats->skipped_updates);
  }
  if (update.updates > 0) {
    stats->policy_loss = update.policy_loss;
    stats->value_loss = update.value_loss;
    stats->approx_kl = update.approx_kl;
    stats->clip_fraction = update.clip_fraction;
    stats->teacher_loss = update.teacher_loss;
  }
  return UpdateStats(*obs_norm_, batch.raw_obs);
}

torch::Tensor Trainer::FetchReferenceAmp(SessionSlot* source) {
  const int64_t M = layout_.amp_obs_size;
  v1::SampleReferenceAmpRequest request;
  request.set_session_id(source->stream->opened().session_id());
  request.set_num_samples(config_.amp_samples);
  request.set_seed(rank_seed() * 1000003 + iteration_);
  auto reference = source->client->SampleReferenceAmp(request);
  if (!reference.ok()) {
    LogLine("iteration %d: no reference AMP samples (%s); discriminator not updated", iteration_ + 1,
            reference.status().message());
    return torch::zeros({0, M});
  }
  absl::StatusOr<torch::Tensor> expert =
      WireToTorch(reference->amp_obs(), "SampleReferenceAmp.amp_obs", v1::FLOAT32,
                  {config_.amp_samples, layout_.wire_amp_obs_size()});
  if (!expert.ok()) {
    LogLine("reference AMP samples unusable, discriminator step skipped: %s",
            std::string(expert.status().message()).c_str());
    return torch::zeros({0, M});
  }
  return expert->narrow(1, 0, M).contiguous();
}

absl::Status Trainer::UpdateDiscriminator(const TrainingBatch& batch, const torch::Tensor& expert,
                                          IterationStats* stats) {
  // Data-parallel ranks step together: all when every rank has both kinds of samples, or none.
  const absl::StatusOr<bool> samples = OnEveryRank(batch.policy_amp.size(0) > 0 && expert.size(0) > 0);
  if (!samples.ok()) return samples.status();
  if (!*samples) return absl::OkStatus();
  if (absl::Status status = UpdateStats(*amp_norm_, torch::cat({expert, batch.policy_amp})); !status.ok()) {
    return status;
  }
  const GradientAverager average = Averager();
  double loss_sum = 0, expert_logit = 0, policy_logit = 0, penalty = 0;
  const torch::Tensor expert_normalized = amp_norm_->Normalize(expert).detach();
  for (int epoch = 0; epoch < config_.discriminator_epochs; ++epoch) {
    // A fresh leaf each epoch: the gradient penalty differentiates through it.
    const torch::Tensor expert_in = expert_normalized.detach().requires_grad_(true);
    const torch::Tensor policy_in =
        amp_norm_->Normalize(batch.policy_amp.slice(0, epoch * config_.amp_samples, (epoch + 1) * config_.amp_samples));
    const torch::Tensor gradient_penalty = discriminator_->GradientPenalty(expert_in);
    AmpLossTerms loss = ComputeAmpLoss(discriminator_->forward(expert_in), discriminator_->forward(policy_in),
                                       gradient_penalty, config_.gradient_penalty_weight);
    const bool finite = std::isfinite(loss.total.item<double>());
    if (!finite && !average) {
      ++stats->skipped_updates;
      continue;
    }
    discriminator_optimizer_->zero_grad();
    if (finite) loss.total.backward();
    if (average) {
      const absl::StatusOr<bool> all_finite = average(discriminator_->parameters(), finite);
      if (!all_finite.ok()) return all_finite.status();
      if (!*all_finite) {
        ++stats->skipped_updates;
        continue;
      }
    }
    discriminator_optimizer_->step();
    loss_sum += loss.total.item<double>();
    expert_logit += loss.expert_logit_mean.item<double>();
    policy_logit += loss.policy_logit_mean.item<double>();
    penalty += loss.gradient_penalty.item<double>();
  }
  const double epochs = config_.discriminator_epochs;
  stats->discriminator_loss = loss_sum / epochs;
  stats->expert_logit = expert_logit / epochs;
  stats->policy_logit = policy_logit / epochs;
  stats->gradient_penalty = penalty / epochs;
  return absl::OkStatus();
}

}  // namespace modskill::learner
