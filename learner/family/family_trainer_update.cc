// FamilyTrainer's learning: PPO on variable time-step GAE, the curriculum's batches, the fit of
// the parameterization network, and the iteration loop.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "common/log.h"
#include "learner/family/family_trainer.h"
#include "learner/family/variable_step_gae.h"
#include "learner/ppo_loss.h"

namespace modskill::learner::family {
namespace {

constexpr double kValueClip = 0.2, kValueCoefficient = 0.5, kMaxGradNorm = 1.0;

}  // namespace

absl::StatusOr<double> FamilyTrainer::Update(const Rollout& rollout) {
  VariableStepRollout steps;
  steps.continuous_reward = torch::stack(rollout.rewards) - torch::stack(rollout.spikes);
  steps.spike_reward = torch::stack(rollout.spikes);
  steps.phase_step = torch::stack(rollout.phase_steps);
  steps.values = torch::stack(rollout.values);
  // A fall and the clip's end both end the motion: neither is bootstrapped (family_trainer.h).
  steps.terminated = torch::stack(rollout.dones);
  steps.last_values = rollout.last_values;
  absl::StatusOr<Advantages> gae = ComputeVariableStepGae(steps, config_.gamma, config_.lambda);
  if (!gae.ok()) return gae.status();
  const torch::Tensor obs = torch::stack(rollout.obs).flatten(0, 1);
  const torch::Tensor actions = torch::stack(rollout.actions).flatten(0, 1);
  const torch::Tensor old_log_probs = torch::stack(rollout.log_probs).flatten(0, 1);
  const torch::Tensor old_values = steps.values.flatten(0, 1);
  const torch::Tensor returns = gae->returns.flatten(0, 1);
  const torch::Tensor advantages = NormalizeAdvantages(gae->advantages.flatten(0, 1));
  const int64_t samples = obs.size(0), minibatch = samples / config_.minibatches;
  double kl = 0;
  int updates = 0;
  for (int epoch = 0; epoch < config_.epochs; ++epoch) {
    const torch::Tensor order = torch::randperm(samples, torch::kLong);
    for (int m = 0; m < config_.minibatches; ++m) {
      const torch::Tensor idx = order.slice(0, m * minibatch, (m + 1) * minibatch);
      const torch::Tensor mb_obs = obs.index_select(0, idx);
      const torch::Tensor mean = model_->Mean(mb_obs);
      const torch::Tensor log_probs = model_->LogProb(mean, actions.index_select(0, idx));
      PpoLossTerms loss = ComputePpoLoss(log_probs, old_log_probs.index_select(0, idx), advantages.index_select(0, idx),
                                         model_->Value(mb_obs), old_values.index_select(0, idx),
                                         returns.index_select(0, idx), config_.clip_ratio, kValueClip,
                                         kValueCoefficient);
      optimizer_->zero_grad();
      loss.total.backward();
      torch::nn::utils::clip_grad_norm_(model_->parameters(), kMaxGradNorm);
      optimizer_->step();
      const double step_kl = EstimateKl(log_probs, old_log_probs.index_select(0, idx)).item<double>();
      learning_rate_->Update(step_kl);
      learning_rate_->ApplyTo(*optimizer_);
      kl += step_kl;
      ++updates;
    }
  }
  // The statistics absorb the batch only now: the behaviour log-probabilities were taken with the
  // ones the epochs use, so PPO's ratios compare the same normalized inputs. (Updated before the
  // epochs, the shift alone gave a KL of 0.004 per update at a learning rate of 1e-9.)
  model_->obs_norm()->Update(obs);
  return updates > 0 ? kl / updates : 0.0;
}

// V(a): the critic at an episode's first observation with the goal's parameters set to a.
std::vector<double> FamilyTrainer::Values(const std::vector<std::vector<double>>& params) {
  torch::NoGradGuard no_grad;
  torch::Tensor obs = template_obs_.unsqueeze(0).repeat({static_cast<int64_t>(params.size()), 1});
  for (size_t k = 0; k < params.size(); ++k) {
    for (size_t d = 0; d < params[k].size(); ++d) obs[k][goal_start_ + d] = params[k][d];
  }
  const torch::Tensor values = model_->Value(obs).to(torch::kDouble).contiguous();
  return std::vector<double>(values.data_ptr<double>(), values.data_ptr<double>() + values.numel());
}

// Once a batch has run its episodes, the curriculum hears how it went and picks the next.
absl::Status FamilyTrainer::AdvanceCurriculum() {
  const int needed = static_cast<int>(batch_.params.size()) * config_.curriculum.episodes_per_param;
  if (batch_episodes_ < needed) return absl::OkStatus();
  if (absl::Status status = curriculum_->ReportBatch(batch_.mode, batch_new_elites_, batch_episodes_); !status.ok()) {
    return status;
  }
  auto next = curriculum_->NextBatch([this](const std::vector<std::vector<double>>& params) { return Values(params); });
  if (!next.ok()) return next.status();
  batch_ = *std::move(next);
  AssignBatch();
  return absl::OkStatus();
}

double FamilyTrainer::FitNet() {
  auto data = EliteTrainingData(*elites_);
  if (!data.ok()) return net_loss_;
  FitOptions options;
  options.epochs = 5;
  options.seed = static_cast<uint64_t>(iteration_);
  auto loss = FitParameterization(net_, *net_optimizer_, *data, options);
  net_fitted_ |= loss.ok();
  return loss.ok() ? *loss : net_loss_;
}

absl::StatusOr<FamilyIterationStats> FamilyTrainer::Iterate() {
  FamilyIterationStats stats;
  Rollout rollout;
  if (absl::Status status = Collect(&rollout, &stats); !status.ok()) return status;
  absl::StatusOr<double> kl = Update(rollout);
  if (!kl.ok()) return kl.status();
  stats.approx_kl = *kl;
  stats.learning_rate = learning_rate_->rate();
  stats.action_std = torch::exp(model_->log_std()).mean().item<double>();
  if (absl::Status status = AdvanceCurriculum(); !status.ok()) return status;
  ++iteration_;
  if (iteration_ % config_.net_every == 0) net_loss_ = FitNet();
  if (stats.episodes > 0) {
    stats.mean_return /= stats.episodes;
    stats.mean_length /= stats.episodes;
    stats.mean_fitness /= stats.episodes;
  }
  stats.iteration = iteration_;
  stats.env_steps = env_steps_;
  stats.elites = elites_->size();
  stats.coverage = EliteCoverage(*elites_, free_dims_, config_.coverage);
  stats.exploration_rate = curriculum_->exploration_rate();
  stats.mode = curriculum_->mode() == CurriculumMode::kExploration ? "exploration" : "refinement";
  stats.net_loss = net_loss_;
  return stats;
}

absl::Status FamilyTrainer::Run(const std::function<bool()>& stop) {
  const auto start = std::chrono::steady_clock::now();
  const double wall_before = wall_s_;
  for (int done = 0; !stop() && (config_.max_iterations <= 0 || done < config_.max_iterations); ++done) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (config_.max_minutes > 0 && elapsed >= 60 * config_.max_minutes) break;
    if (config_.max_env_steps > 0 && env_steps_ >= config_.max_env_steps) break;
    absl::StatusOr<FamilyIterationStats> stats = Iterate();
    if (!stats.ok()) return stats.status();
    wall_s_ = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats->wall_s = wall_s_;
    if (absl::Status status = AppendProgress(*stats); !status.ok()) return status;
    if (absl::Status status = SaveCheckpoint(); !status.ok()) return status;
    if (absl::Status status = ExportPolicyFile(); !status.ok()) return status;
    LogLine("family it %d steps %d return %.2f len %.1f F %.3f elites %d coverage %.3f %s", stats->iteration,
            stats->env_steps, stats->mean_return, stats->mean_length, stats->mean_fitness, stats->elites,
            stats->coverage, stats->mode);
  }
  return absl::OkStatus();
}

absl::Status FamilyTrainer::Close() { return stream_->Close(); }

}  // namespace modskill::learner::family
