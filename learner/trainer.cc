#include "learner/trainer.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "learner/amp_loss.h"
#include "learner/evaluation.h"
#include "learner/gae.h"
#include "learner/policy_export.h"
#include "learner/ppo_loss.h"
#include "server/core/env/tracking_env.h"

namespace modskill::learner {
namespace {

using Clock = std::chrono::steady_clock;

// A wire tensor as a torch tensor of `shape` (copied: the message buffer is reused).
torch::Tensor ToTorch(const v1::Tensor& tensor, std::vector<int64_t> shape) {
  switch (tensor.dtype()) {
    case v1::FLOAT32:
      return torch::from_blob(const_cast<char*>(tensor.data().data()), shape, torch::kFloat32).clone();
    case v1::UINT8:
      return torch::from_blob(const_cast<char*>(tensor.data().data()), shape, torch::kUInt8).to(torch::kFloat32);
    case v1::INT32:
      return torch::from_blob(const_cast<char*>(tensor.data().data()), shape, torch::kInt32).clone();
    default:
      return torch::Tensor();
  }
}

bool AllFinite(const std::vector<torch::Tensor>& tensors) {
  for (const torch::Tensor& t : tensors) {
    if (!torch::isfinite(t).all().item<bool>()) return false;
  }
  return true;
}

// Torch's intra-op threads for one phase (the update, while the servers wait), restored after it.
class ScopedTorchThreads {
 public:
  explicit ScopedTorchThreads(int threads) : previous_(at::get_num_threads()) {
    if (threads > 0 && threads != previous_) at::set_num_threads(threads);
  }
  ~ScopedTorchThreads() {
    if (at::get_num_threads() != previous_) at::set_num_threads(previous_);
  }

 private:
  int previous_;
};

}  // namespace

Trainer::Trainer(const TrainerConfig& config)
    : config_(config),
      curriculum_(config.curriculum_start > 0 ? config.curriculum_start : config.termination_distance,
                  config.curriculum_end > 0 ? config.curriculum_end : config.termination_distance),
      generator_(at::detail::createCPUGenerator(config.seed)),
      acting_generator_(at::detail::createCPUGenerator(config.seed * 1000003 + 7919)) {}

Trainer::~Trainer() { DiscardCollection(); }

absl::StatusOr<std::unique_ptr<Trainer>> Trainer::Create(const TrainerConfig& config) {
  if (absl::Status status = config.Validate(); !status.ok()) return status;
  std::error_code error;
  std::filesystem::create_directories(config.run_dir, error);
  if (error) return absl::PermissionDeniedError(absl::StrCat("--run_dir ", config.run_dir, ": ", error.message()));
  const std::string probe = config.run_dir + "/.writable";
  if (absl::Status status = WriteFileAtomically(probe, "ok"); !status.ok()) {
    return absl::PermissionDeniedError(absl::StrCat("--run_dir ", config.run_dir, ": not writable: ", status.message()));
  }
  std::filesystem::remove(probe, error);
  torch::manual_seed(config.seed);
  // Every iteration allocates and frees tens of MB of rollout and AMP tensors; glibc returns such
  // blocks to the kernel, and faulting them back in cost ~0.15 s per 100 MB. Keep them.
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::unique_ptr<Trainer> trainer(new Trainer(config));
  ServerPoolOptions pool;
  pool.servers = config.servers;
  pool.token = config.token;
  pool.tls_ca_file = config.tls_ca_file;
  pool.envs_per_server = config.envs_per_server;
  pool.sessions_per_server = config.sessions_per_server;
  pool.session.set_part_layout(config.part_layout);
  for (const std::string& clip : config.motions) pool.session.add_motions(clip);
  pool.session.set_termination(v1::TRAINING);
  const bool residual = ActionModeOf(config) == ActionMode::kResidual;
  pool.session.set_action_mode(residual ? v1::RESIDUAL : v1::ABSOLUTE);
  if (residual) pool.session.set_residual_scale(static_cast<float>(config.residual_scale));
  // The curriculum's starting distance; every action message then carries the current one.
  pool.session.set_termination_distance(static_cast<float>(trainer->curriculum_.distance()));
  pool.session.set_termination_bodies(TerminationBodiesOf(config) == TerminationBodies::kNoFeet ? v1::NO_FEET
                                                                                                : v1::ALL);
  pool.session.set_amp_obs(v1::FULL);
  trainer->servers_ = std::make_unique<ServerPool>(pool);
  if (absl::Status status = trainer->WaitForServers(); !status.ok()) return status;
  if (absl::Status status = trainer->BuildNetworks(*trainer->servers_->spec()); !status.ok()) return status;
  const std::string checkpoint = config.run_dir + "/checkpoint.pt";
  if (config.resume) {
    if (absl::Status status = trainer->LoadCheckpoint(checkpoint); !status.ok()) return status;
    LogLine("resumed %s at iteration %d (%lld env steps)", checkpoint, trainer->iteration_,
            static_cast<long long>(trainer->env_steps_));
  }
  if (absl::Status status = WriteFileAtomically(config.run_dir + "/config.json", config.ToJson()); !status.ok()) {
    return status;
  }
  return trainer;
}

absl::Status Trainer::WaitForServers() {
  const absl::Time start = absl::Now();
  bool announced = false;
  while (true) {
    if (servers_->Reconnect(static_cast<int64_t>(config_.seed) + iteration_) > 0) return absl::OkStatus();
    const absl::Duration waited = absl::Now() - start;
    if (waited > absl::Seconds(config_.server_timeout_s)) {
      std::string tried;
      for (const auto& slot : servers_->slots()) absl::StrAppend(&tried, "\n  ", slot->server, ": ", slot->last_error);
      return absl::UnavailableError(absl::StrCat("no simulation server answered for ",
                                                 absl::FormatDuration(waited), " (--server_timeout_s):", tried));
    }
    if (!announced) {
      LogLine("waiting for a simulation server (up to %.0f s)", config_.server_timeout_s);
      announced = true;
    }
    absl::SleepFor(absl::Milliseconds(500));
  }
}

absl::Status Trainer::BuildNetworks(const v1::EnvSpec& spec) {
  spec_ = spec;
  layout_.obs_size = spec.obs_size();
  layout_.action_size = spec.action_size();
  layout_.amp_obs_size = static_cast<int64_t>(spec.amp_history()) * spec.amp_obs_per_frame();
  for (const v1::BodyPart& part : spec.parts()) {
    PartSlices slices;
    slices.name = part.name();
    slices.obs_start = part.obs().start();
    slices.obs_size = part.obs().size();
    slices.action_start = part.action().start();
    slices.action_size = part.action().size();
    layout_.parts.push_back(slices);
  }
  if (absl::Status status = layout_.Validate(); !status.ok()) {
    return absl::FailedPreconditionError(absl::StrCat("server env spec: ", status.message()));
  }
  policy_ = ModSkillPolicy(layout_, config_.model);
  critic_ = Critic(layout_.obs_size, config_.model.critic_hidden);
  discriminator_ = AmpDiscriminator(layout_.amp_obs_size, config_.model.discriminator_hidden);
  obs_norm_ = RunningMeanStd(layout_.obs_size);
  amp_norm_ = RunningMeanStd(layout_.amp_obs_size);
  std::vector<torch::Tensor> parameters = policy_->parameters();
  for (const torch::Tensor& p : critic_->parameters()) parameters.push_back(p);
  optimizer_ = std::make_unique<torch::optim::Adam>(parameters, torch::optim::AdamOptions(config_.learning_rate));
  discriminator_optimizer_ = std::make_unique<torch::optim::Adam>(
      discriminator_->parameters(), torch::optim::AdamOptions(config_.discriminator_learning_rate));
  return absl::OkStatus();
}

absl::Status Trainer::Run(const std::function<void(const IterationStats&)>& on_iteration,
                          const std::atomic<bool>* stop) {
  const int last = iteration_ + config_.iterations;
  // A collection still running when the run ends was collected for an update that will not come.
  struct DiscardAtExit {
    Trainer* trainer;
    ~DiscardAtExit() { trainer->DiscardCollection(); }
  } discard{this};
  while (iteration_ < last) {
    if (stop != nullptr && stop->load()) break;
    absl::StatusOr<IterationStats> stats;
    try {
      torch::AutoGradMode grad(true);  // whatever the caller's mode, the update needs gradients
      stats = Iterate();
    } catch (const std::exception& e) {
      std::string message = e.what();
      return absl::InternalError(absl::StrCat("iteration ", iteration_ + 1, ": ", message.substr(0, message.find('\n'))));
    }
    if (!stats.ok()) return stats.status();
    history_.push_back(*stats);
    if (on_iteration) on_iteration(*stats);
    if (iteration_ % config_.checkpoint_every == 0 || iteration_ == last) {
      if (absl::Status status = SaveCheckpoint(config_.run_dir + "/checkpoint.pt"); !status.ok()) return status;
      if (absl::Status status = ExportPolicy(config_.run_dir + "/policy.pt"); !status.ok()) return status;
    }
  }
  return absl::OkStatus();
}

// One session's share of an iteration's experience, [T, n, ...].
struct Trainer::SlotRollout {
  SessionSlot* slot = nullptr;
  int n = 0;
  bool failed = false;
  torch::Tensor obs, actions, log_prob, values, task_reward, dones, truncated, amp_next;
  torch::Tensor next_obs;  // observation after the last step (raw)
  std::vector<torch::Tensor> raw_obs;  // for the normalizer, after the update
  torch::Tensor reward_terms_sum;
};

// One collection: every live session's rollout, and what it ran under.
struct Trainer::Collection {
  std::vector<SlotRollout> rollouts;
  double termination_distance = 0;
  int64_t policy_version = 0;  // of the weights that acted
};

// The iteration's experience from every usable session, flattened to [T * N, ...].
struct Trainer::TrainingBatch {
  torch::Tensor obs;  // normalized with the statistics of the iteration's start
  torch::Tensor actions, old_log_prob, old_values, advantages, returns;
  torch::Tensor raw_obs;      // for the normalizer
  // AMP observations of live (not ended) rows drawn at random for the discriminator,
  // [amp_samples * discriminator_epochs, M]: copying all T * N rows of 2320 floats cost more
  // than the discriminator step itself.
  torch::Tensor policy_amp;
  double task_sum = 0, amp_sum = 0, samples = 0;
  torch::Tensor terms_sum;
  int live_sessions = 0;
};

absl::StatusOr<IterationStats> Trainer::Iterate() {
  IterationStats stats;
  const auto start = Clock::now();
  Collection collection;
  if (pending_.valid()) {
    collection = std::move(*pending_.get());  // collected while the last update ran
  } else {
    servers_->Reconnect(static_cast<int64_t>(config_.seed) + iteration_ + 1);
    if (servers_->Alive().empty()) {
      if (absl::Status status = WaitForServers(); !status.ok()) return status;
    }
    collection = Collect(LiveNetworks());
  }
  stats.collect_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  stats.termination_distance = collection.termination_distance;
  stats.policy_lag = static_cast<int>(policy_version_ - collection.policy_version);
  std::vector<SlotRollout*> usable;
  for (SlotRollout& r : collection.rollouts) {
    if (!r.failed) usable.push_back(&r);
  }
  if (usable.empty()) {
    // Every server failed during this iteration: nothing to learn from; try again.
    stats.iteration = iteration_;
    stats.env_steps = env_steps_;
    LogLine("iteration %d: every session failed while collecting; retrying", iteration_ + 1);
    return stats;
  }
  SummarizeEpisodes(&stats);
  const ScopedTorchThreads threads(UpdateThreads());  // the servers wait from here on
  TrainingBatch batch = ComputeReturns(usable);
  if (stats.policy_lag > 0) CenterOnCurrentPolicy(&batch);
  const torch::Tensor expert =
      config_.amp_reward_weight > 0 ? FetchReferenceAmp(usable.front()->slot) : torch::Tensor();
  if (config_.report_every > 0 && (iteration_ + 1) % config_.report_every == 0) ReportFailures();
  if (config_.collect_during_update) {
    servers_->Reconnect(static_cast<int64_t>(config_.seed) + iteration_ + 2);
    if (!servers_->Alive().empty()) StartCollection();
  }
  const auto update_start = Clock::now();
  UpdatePolicy(batch, &stats);
  ++policy_version_;
  if (expert.defined()) UpdateDiscriminator(batch, expert, &stats);
  ++iteration_;
  env_steps_ += static_cast<int64_t>(batch.samples);
  stats.update_seconds = std::chrono::duration<double>(Clock::now() - update_start).count();
  stats.env_steps_per_second = batch.samples / std::chrono::duration<double>(Clock::now() - start).count();
  Summarize(batch, &stats);
  return stats;
}

int Trainer::UpdateThreads() const {
  // Collecting during the update, both share the cores with the servers: OpenMP threads spinning
  // against each other cost 2x (bench/learner_throughput_bench).
  return config_.collect_during_update ? 0 : config_.update_threads;
}

ActingNetworks Trainer::LiveNetworks() { return ActingNetworks{policy_, critic_, obs_norm_, policy_version_}; }

void Trainer::StartCollection() {
  if (!snapshot_.policy) {
    snapshot_.policy = ModSkillPolicy(layout_, config_.model);
    snapshot_.critic = Critic(layout_.obs_size, config_.model.critic_hidden);
    snapshot_.obs_norm = RunningMeanStd(layout_.obs_size);
  }
  CopyModuleState(*policy_, *snapshot_.policy);
  CopyModuleState(*critic_, *snapshot_.critic);
  CopyModuleState(*obs_norm_, *snapshot_.obs_norm);
  snapshot_.version = policy_version_;
  pending_ = std::async(std::launch::async, [this] {
    at::set_num_threads(1);  // the update and the servers have the cores
    return std::make_shared<Collection>(Collect(snapshot_));
  });
}

void Trainer::DiscardCollection() {
  if (!pending_.valid()) return;
  try {
    pending_.get();
  } catch (const std::exception& e) {
    LogLine("the collection running at the end of the run failed: %s", e.what());
  }
}

Trainer::Collection Trainer::Collect(ActingNetworks acting) {
  const int T = config_.horizon;
  const int64_t O = layout_.obs_size, A = layout_.action_size, M = layout_.amp_obs_size;
  Collection collection;
  collection.termination_distance = curriculum_.distance();
  collection.policy_version = acting.version;
  std::vector<SlotRollout>& rollouts = collection.rollouts;
  for (SessionSlot* slot : servers_->Alive()) {
    SlotRollout r;
    r.slot = slot;
    r.n = slot->num_envs();
    r.obs = torch::zeros({T, r.n, O});
    r.actions = torch::zeros({T, r.n, A});
    r.log_prob = torch::zeros({T, r.n});
    r.values = torch::zeros({T, r.n});
    r.task_reward = torch::zeros({T, r.n});
    r.dones = torch::zeros({T, r.n});
    r.truncated = torch::zeros({T, r.n});
    r.amp_next = torch::zeros({T, r.n, M});
    r.reward_terms_sum = torch::zeros({spec_.reward_terms_size()}, torch::kFloat64);
    // Every action message carries the distance, so a session that reopens gets it too.
    slot->stream->SetTerminationDistance(static_cast<float>(collection.termination_distance));
    rollouts.push_back(std::move(r));
  }
  auto fail = [&](SlotRollout& r, const absl::Status& status) {
    r.failed = true;
    servers_->MarkDead(r.slot, status);
  };
  for (size_t i = 0; i < servers_->slots().size(); ++i) slot_index_[servers_->slots()[i].get()] = i;
  if (episode_return_.size() < servers_->slots().size()) {
    episode_return_.resize(servers_->slots().size());
    episode_length_.resize(servers_->slots().size());
  }
  for (SlotRollout& r : rollouts) {
    auto& returns = episode_return_[slot_index_[r.slot]];
    auto& lengths = episode_length_[slot_index_[r.slot]];
    if (returns.size() != static_cast<size_t>(r.n)) {
      returns.assign(r.n, 0.0);
      lengths.assign(r.n, 0);
    }
    // Where the slot's envs are: the last result, or the first observation of a new session.
    const SimulationStream& stream = *r.slot->stream;
    const bool fresh = stream.opened().initial().step() == 0 && stream.result().obs().data().empty();
    const v1::StepResult& result = fresh ? stream.opened().initial() : stream.result();
    if (absl::Status status = Act(r, 0, ToTorch(result.obs(), {r.n, O}), acting); !status.ok()) fail(r, status);
  }
  for (int t = 0; t < T; ++t) {
    for (SlotRollout& r : rollouts) {
      if (r.failed) continue;
      if (absl::Status status = r.slot->stream->ReceiveResult(); !status.ok()) {
        fail(r, status);
        continue;
      }
      RecordStep(r, t);
      const torch::Tensor next = ToTorch(r.slot->stream->result().obs(), {r.n, O});
      if (t + 1 < T) {
        if (absl::Status status = Act(r, t + 1, next, acting); !status.ok()) fail(r, status);
      } else {
        r.next_obs = next;
      }
    }
  }
  const size_t keep = 200;
  if (recent_returns_.size() > keep) {
    recent_returns_.erase(recent_returns_.begin(), recent_returns_.end() - keep);
    recent_lengths_.erase(recent_lengths_.begin(), recent_lengths_.end() - keep);
    recent_tracked_.erase(recent_tracked_.begin(), recent_tracked_.end() - keep);
  }
  return collection;
}

// Observations are normalized with the statistics of the iteration's start and stored
// normalized, so that PPO's ratios compare the same inputs; the statistics absorb the
// iteration's observations after the update. (With sigma = exp(-2.9), drifting inputs alone
// would move log-probabilities by tens of nats.)
absl::Status Trainer::Act(SlotRollout& r, int t, const torch::Tensor& obs, ActingNetworks& acting) {
  torch::NoGradGuard no_grad;
  const torch::Tensor normalized = acting.obs_norm->Normalize(obs);
  r.raw_obs.push_back(obs);
  const torch::Tensor mean = acting.policy->forward(normalized);
  const torch::Tensor log_std = acting.policy->log_std();
  const torch::Tensor action = mean + log_std.exp() * torch::randn(mean.sizes(), acting_generator_);
  r.obs[t].copy_(normalized);
  r.actions[t].copy_(action);
  r.log_prob[t].copy_(ModSkillPolicyImpl::LogProb(mean, log_std, action));
  r.values[t].copy_(acting.critic->forward(normalized));
  const torch::Tensor contiguous = action.contiguous();
  return r.slot->stream->SendActions(contiguous.data_ptr<float>());
}

void Trainer::RecordStep(SlotRollout& r, int t) {
  const v1::StepResult& result = r.slot->stream->result();
  const torch::Tensor reward = ToTorch(result.reward(), {r.n});
  const torch::Tensor done = ToTorch(result.done(), {r.n});
  const torch::Tensor truncated = ToTorch(result.truncated(), {r.n});
  r.task_reward[t].copy_(reward);
  r.dones[t].copy_(done);
  r.truncated[t].copy_(truncated);
  r.amp_next[t].copy_(ToTorch(result.amp_obs(), {r.n, layout_.amp_obs_size}));
  r.reward_terms_sum += ToTorch(result.reward_terms(), {r.n, spec_.reward_terms_size()}).to(torch::kFloat64).sum(0);
  auto& returns = episode_return_[slot_index_[r.slot]];
  auto& lengths = episode_length_[slot_index_[r.slot]];
  const float* reward_data = reward.data_ptr<float>();
  const float* done_data = done.data_ptr<float>();
  const float* truncated_data = truncated.data_ptr<float>();
  for (int i = 0; i < r.n; ++i) {
    returns[i] += reward_data[i];
    ++lengths[i];
    if (done_data[i] > 0.5f) {
      recent_returns_.push_back(returns[i]);
      recent_lengths_.push_back(lengths[i]);
      recent_tracked_.push_back(truncated_data[i] > 0.5f ? 1.0 : 0.0);
      returns[i] = 0;
      lengths[i] = 0;
    }
  }
  RecordEpisodeEnds(r.slot, result);
}

Trainer::TrainingBatch Trainer::ComputeReturns(const std::vector<SlotRollout*>& usable) {
  torch::NoGradGuard no_grad;
  const int T = config_.horizon;
  const int64_t O = layout_.obs_size, A = layout_.action_size, M = layout_.amp_obs_size;
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
    actions.push_back(r->actions.reshape({-1, A}));
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
    proximal.push_back(ModSkillPolicyImpl::LogProb(policy_->forward(batch->obs.slice(0, begin, end)), log_std,
                                                   batch->actions.slice(0, begin, end)));
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

// PPO (Schulman et al. 2017). A non-finite loss skips its minibatch; non-finite weights after the
// update roll back to the weights it started from. Iterate gives the update phases
// config.update_threads torch threads while the servers wait.
void Trainer::UpdatePolicy(const TrainingBatch& batch, IterationStats* stats) {
  std::vector<torch::Tensor> snapshot;
  for (const torch::Tensor& p : optimizer_->param_groups()[0].params()) snapshot.push_back(p.detach().clone());
  const torch::Tensor log_std = policy_->log_std();
  double policy_loss = 0, value_loss = 0, approx_kl = 0, clip_fraction = 0;
  int updates = 0;
  const int64_t size = batch.obs.size(0);
  const int64_t minibatch = std::min<int64_t>(config_.minibatch_size, size);
  for (int epoch = 0; epoch < config_.epochs; ++epoch) {
    const torch::Tensor order = torch::randperm(size, generator_);
    for (int64_t begin = 0; begin + minibatch <= size; begin += minibatch) {
      const torch::Tensor index = order.slice(0, begin, begin + minibatch);
      const torch::Tensor obs = batch.obs.index_select(0, index);
      const torch::Tensor new_log_prob =
          ModSkillPolicyImpl::LogProb(policy_->forward(obs), log_std, batch.actions.index_select(0, index));
      PpoLossTerms loss = ComputePpoLoss(new_log_prob, batch.old_log_prob.index_select(0, index),
                                         batch.advantages.index_select(0, index), critic_->forward(obs),
                                         batch.old_values.index_select(0, index), batch.returns.index_select(0, index),
                                         config_.clip_ratio, config_.value_clip, config_.value_coefficient);
      if (!std::isfinite(loss.total.item<double>())) {
        ++stats->skipped_updates;
        continue;
      }
      optimizer_->zero_grad();
      loss.total.backward();
      torch::nn::utils::clip_grad_norm_(optimizer_->param_groups()[0].params(), config_.max_grad_norm);
      optimizer_->step();
      policy_loss += loss.policy_loss.item<double>();
      value_loss += loss.value_loss.item<double>();
      approx_kl += loss.approx_kl.item<double>();
      clip_fraction += loss.clip_fraction.item<double>();
      ++updates;
    }
  }
  if (!AllFinite(optimizer_->param_groups()[0].params())) {
    torch::NoGradGuard no_grad;
    auto& params = optimizer_->param_groups()[0].params();
    for (size_t i = 0; i < params.size(); ++i) params[i].copy_(snapshot[i]);
    LogLine("iteration %d: non-finite weights after the update; kept the last good ones", iteration_ + 1);
    ++stats->skipped_updates;
  }
  if (stats->skipped_updates > 0) {
    LogLine("iteration %d: skipped %d updates with a non-finite loss", iteration_ + 1, stats->skipped_updates);
  }
  if (updates > 0) {
    stats->policy_loss = policy_loss / updates;
    stats->value_loss = value_loss / updates;
    stats->approx_kl = approx_kl / updates;
    stats->clip_fraction = clip_fraction / updates;
  }
  obs_norm_->Update(batch.raw_obs);
}

torch::Tensor Trainer::FetchReferenceAmp(SessionSlot* source) {
  const int64_t M = layout_.amp_obs_size;
  v1::SampleReferenceAmpRequest request;
  request.set_session_id(source->stream->opened().session_id());
  request.set_num_samples(config_.amp_samples);
  request.set_seed(config_.seed * 1000003 + iteration_);
  auto reference = source->client->SampleReferenceAmp(request);
  if (!reference.ok()) {
    LogLine("iteration %d: no reference AMP samples (%s); discriminator not updated", iteration_ + 1,
            reference.status().message());
    return torch::zeros({0, M});
  }
  return ToTorch(reference->amp_obs(), {config_.amp_samples, M});
}

void Trainer::UpdateDiscriminator(const TrainingBatch& batch, const torch::Tensor& expert, IterationStats* stats) {
  if (batch.policy_amp.size(0) == 0 || expert.size(0) == 0) return;
  amp_norm_->Update(torch::cat({expert, batch.policy_amp}));
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
    if (!std::isfinite(loss.total.item<double>())) {
      ++stats->skipped_updates;
      continue;
    }
    discriminator_optimizer_->zero_grad();
    loss.total.backward();
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
}

void Trainer::Summarize(const TrainingBatch& batch, IterationStats* stats) {
  stats->iteration = iteration_;
  stats->env_steps = env_steps_;
  stats->mean_task_reward = batch.task_sum / batch.samples;
  stats->mean_amp_reward = batch.amp_sum / batch.samples;
  const int64_t terms = std::min<int64_t>(batch.terms_sum.size(0), 8);
  for (int64_t k = 0; k < terms; ++k) stats->reward_terms[k] = batch.terms_sum[k].item<double>() / batch.samples;
  stats->live_sessions = batch.live_sessions;
}

void Trainer::SummarizeEpisodes(IterationStats* stats) {
  if (!recent_returns_.empty()) {
    double r = 0, l = 0, tracked = 0;
    for (size_t i = 0; i < recent_returns_.size(); ++i) {
      r += recent_returns_[i];
      l += recent_lengths_[i];
      tracked += recent_tracked_[i];
    }
    stats->mean_episode_return = r / recent_returns_.size();
    stats->mean_episode_length = l / recent_lengths_.size();
    stats->tracked_share = tracked / recent_tracked_.size();
    curriculum_.Update(stats->tracked_share);
  }
}

void Trainer::RecordEpisodeEnds(SessionSlot* slot, const v1::StepResult& result) {
  // Every field's size was checked against the session when the result arrived (CheckStepResult).
  const int n = slot->num_envs();
  const std::string& done = result.done().data();
  const std::string& truncated = result.truncated().data();
  std::vector<int32_t> clip(n), frame(n);
  std::memcpy(clip.data(), result.ended_clip_id().data().data(), sizeof(int32_t) * n);
  std::memcpy(frame.data(), result.ended_frame().data().data(), sizeof(int32_t) * n);
  const int parts = result.part_error().shape_size() == 2 ? static_cast<int>(result.part_error().shape(1)) : 0;
  std::vector<float> part_error(static_cast<size_t>(n) * parts);
  if (parts > 0) std::memcpy(part_error.data(), result.part_error().data().data(), sizeof(float) * part_error.size());
  PendingReports& pending = pending_reports_[slot];
  if (pending.generation != slot->generation) pending = PendingReports{slot->generation, {}};
  for (int i = 0; i < n; ++i) {
    if (!done[i]) continue;
    const std::string& name = slot->stream->clip_name(clip[i]);
    if (name.empty()) continue;
    v1::ClipFailure failure;
    failure.set_clip(name);
    failure.set_frame(frame[i]);
    failure.set_terminated(!truncated[i]);
    bool finite = true;
    for (int p = 0; p < parts; ++p) finite &= std::isfinite(part_error[i * parts + p]);
    if (failure.terminated() && finite) {
      for (int p = 0; p < parts; ++p) failure.add_part_errors(part_error[i * parts + p]);
    }
    auto& outcome = clip_outcomes_[failure.clip()];
    (failure.terminated() ? outcome.first : outcome.second) += 1;
    pending.failures.push_back(std::move(failure));
  }
}

void Trainer::ReportFailures() {
  // The discriminator goes along, so the servers can hold generated clips to ModSkill's rule.
  std::string discriminator;
  if (config_.amp_reward_weight > 0) {
    auto scorer = ExportDiscriminatorScorer(*discriminator_, *amp_norm_);
    if (scorer.ok()) {
      discriminator = *std::move(scorer);
    } else {
      LogLine("discriminator not sent: %s", scorer.status().message());
    }
  }
  for (SessionSlot* slot : servers_->Alive()) {
    PendingReports& pending = pending_reports_[slot];
    if (pending.generation != slot->generation || pending.failures.empty()) continue;
    v1::ReportFailuresRequest request;
    request.set_session_id(slot->stream->opened().session_id());
    request.set_discriminator(discriminator);
    for (v1::ClipFailure& failure : pending.failures) *request.add_failures() = std::move(failure);
    pending.failures.clear();
    auto state = slot->client->ReportFailures(request);
    if (!state.ok()) LogLine("failure report to %s not taken: %s", slot->server, state.status().message());
  }
  // The hardest clips so far: highest failure rate among those seen at least 5 times.
  std::vector<std::pair<double, std::string>> rates;
  for (const auto& [clip, outcome] : clip_outcomes_) {
    const int64_t total = outcome.first + outcome.second;
    if (total >= 5) rates.emplace_back(static_cast<double>(outcome.first) / total, clip);
  }
  std::sort(rates.rbegin(), rates.rend());
  std::string hardest;
  for (size_t k = 0; k < std::min<size_t>(5, rates.size()); ++k) {
    absl::StrAppend(&hardest, k ? ", " : "", rates[k].second, " ", static_cast<int>(100 * rates[k].first), "%");
  }
  if (!hardest.empty()) LogLine("hardest clips (episodes failed): %s", hardest);
}

absl::Status Trainer::SaveCheckpoint(const std::string& path) {
  try {
    torch::serialize::OutputArchive archive;
    auto add_module = [&](const char* key, const torch::nn::Module& module) {
      torch::serialize::OutputArchive sub;
      module.save(sub);
      archive.write(key, sub);
    };
    add_module("policy", *policy_);
    add_module("critic", *critic_);
    add_module("discriminator", *discriminator_);
    add_module("obs_norm", *obs_norm_);
    add_module("amp_norm", *amp_norm_);
    torch::serialize::OutputArchive optimizer, discriminator_optimizer;
    optimizer_->save(optimizer);
    discriminator_optimizer_->save(discriminator_optimizer);
    archive.write("optimizer", optimizer);
    archive.write("discriminator_optimizer", discriminator_optimizer);
    archive.write("iteration", torch::tensor(static_cast<int64_t>(iteration_)));
    archive.write("env_steps", torch::tensor(static_cast<int64_t>(env_steps_)));
    archive.write("obs_size", torch::tensor(layout_.obs_size));
    archive.write("action_size", torch::tensor(layout_.action_size));
    archive.write("amp_obs_size", torch::tensor(layout_.amp_obs_size));
    archive.write("action_mode", torch::tensor(static_cast<int64_t>(ActionModeOf(config_))));
    archive.write("residual_scale", torch::tensor(config_.residual_scale, torch::kFloat64));
    archive.write("termination_distance", torch::tensor(curriculum_.distance(), torch::kFloat64));
    std::ostringstream out(std::ios::binary);
    archive.save_to(out);
    return WriteFileAtomically(path, out.str());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat(path, ": cannot write checkpoint: ", message.substr(0, message.find('\n'))));
  }
}

absl::Status Trainer::LoadCheckpoint(const std::string& path) {
  auto bytes = ReadFileToString(path, size_t{4} << 30);
  if (!bytes.ok()) return bytes.status();
  try {
    torch::serialize::InputArchive archive;
    std::istringstream in(*bytes, std::ios::binary);
    archive.load_from(in);
    torch::Tensor obs_size, action_size, amp_obs_size, iteration, env_steps;
    archive.read("obs_size", obs_size);
    archive.read("action_size", action_size);
    archive.read("amp_obs_size", amp_obs_size);
    if (obs_size.item<int64_t>() != layout_.obs_size || action_size.item<int64_t>() != layout_.action_size ||
        amp_obs_size.item<int64_t>() != layout_.amp_obs_size) {
      return absl::FailedPreconditionError(
          absl::StrCat(path, ": trained with obs ", obs_size.item<int64_t>(), ", actions ", action_size.item<int64_t>(),
                       ", AMP obs ", amp_obs_size.item<int64_t>(), "; the server has ", layout_.obs_size, ", ",
                       layout_.action_size, ", ", layout_.amp_obs_size));
    }
    auto load_module = [&](const char* key, torch::nn::Module& module) {
      torch::serialize::InputArchive sub;
      archive.read(key, sub);
      module.load(sub);
    };
    // Checkpoints from before action modes were trained in absolute mode.
    torch::Tensor action_mode = torch::tensor(static_cast<int64_t>(ActionMode::kAbsolute));
    torch::Tensor residual_scale = torch::tensor(config_.residual_scale, torch::kFloat64);
    archive.try_read("action_mode", action_mode);
    archive.try_read("residual_scale", residual_scale);
    const auto trained_mode = static_cast<ActionMode>(action_mode.item<int64_t>());
    if (trained_mode != ActionModeOf(config_) ||
        (trained_mode == ActionMode::kResidual && residual_scale.item<double>() != config_.residual_scale)) {
      return absl::FailedPreconditionError(absl::StrCat(
          path, ": trained with --action_mode ", ActionModeName(trained_mode),
          trained_mode == ActionMode::kResidual ? absl::StrCat(" --residual_scale ", residual_scale.item<double>()) : "",
          "; resume with the same flags"));
    }
    load_module("policy", *policy_);
    load_module("critic", *critic_);
    load_module("discriminator", *discriminator_);
    load_module("obs_norm", *obs_norm_);
    load_module("amp_norm", *amp_norm_);
    torch::serialize::InputArchive optimizer, discriminator_optimizer;
    archive.read("optimizer", optimizer);
    archive.read("discriminator_optimizer", discriminator_optimizer);
    optimizer_->load(optimizer);
    discriminator_optimizer_->load(discriminator_optimizer);
    archive.read("iteration", iteration);
    archive.read("env_steps", env_steps);
    torch::Tensor termination_distance;
    if (archive.try_read("termination_distance", termination_distance)) {
      curriculum_.set_distance(termination_distance.item<double>());
    }
    iteration_ = static_cast<int>(iteration.item<int64_t>());
    env_steps_ = env_steps.item<int64_t>();
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a loadable training checkpoint (different preset or layout?): ",
                     message.substr(0, message.find('\n'))));
  }
  return absl::OkStatus();
}

absl::Status Trainer::ExportPolicy(const std::string& path) {
  const PolicySpec spec = PolicySpecOf(spec_, ActionMapping{ActionModeOf(config_), config_.residual_scale});
  return learner::ExportPolicy(policy_, obs_norm_, spec, path);
}

}  // namespace modskill::learner
