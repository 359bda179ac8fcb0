#include "learner/trainer.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "common/wire/policy_enums.h"
#include "learner/evaluation.h"
#include "learner/part_retraining.h"
#include "learner/ppo_update.h"
#include "learner/trainer_phases.h"

namespace modskill::learner {
namespace {

using Clock = std::chrono::steady_clock;

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
      acting_generator_(at::detail::createCPUGenerator(rank_seed() * 1000003 + 7919)),
      held_noise_(config_.noise_hold_steps) {}

Trainer::~Trainer() { DiscardCollection(); }

absl::StatusOr<std::unique_ptr<Trainer>> Trainer::Create(const TrainerConfig& config) {
  if (absl::Status status = config.Validate(); !status.ok()) return status;
  if (config.data_parallel.rank == 0) {  // the other ranks write nothing
    std::error_code error;
    std::filesystem::create_directories(config.run_dir, error);
    if (error) return absl::PermissionDeniedError(absl::StrCat("--run_dir ", config.run_dir, ": ", error.message()));
    const std::string probe = config.run_dir + "/.writable";
    if (absl::Status status = WriteFileAtomically(probe, "ok"); !status.ok()) {
      return absl::PermissionDeniedError(absl::StrCat("--run_dir ", config.run_dir, ": not writable: ", status.message()));
    }
    std::filesystem::remove(probe, error);
  }
  torch::manual_seed(config.seed);
  // Every iteration allocates and frees tens of MB of rollout and AMP tensors; glibc returns such
  // blocks to the kernel, and faulting them back in cost ~0.15 s per 100 MB. Keep them.
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::unique_ptr<Trainer> trainer(new Trainer(config));
  if (config.data_parallel.world_size > 1) {
    if (absl::Status status = trainer->JoinRanks(); !status.ok()) return trainer->ReportToRanks(status);
  }
  if (!IsTrackingTask(config.task)) {
    if (absl::Status status = trainer->PrepareTask(); !status.ok()) return trainer->ReportToRanks(status);
  }
  trainer->ChooseReferenceFrames();  // before the sessions open: it sets their observation
  absl::StatusOr<std::unique_ptr<ServerPool>> pool = ServerPool::Create(trainer->PoolOptions());
  if (!pool.ok()) return trainer->ReportToRanks(pool.status());
  trainer->servers_ = *std::move(pool);
  if (absl::Status status = trainer->WaitForServers(); !status.ok()) return trainer->ReportToRanks(status);
  if (absl::Status status = trainer->PrepareState(); !status.ok()) return trainer->ReportToRanks(status);
  if (trainer->writes_run_dir()) {
    if (absl::Status status = WriteFileAtomically(config.run_dir + "/config.json", trainer->config_.ToJson());
        !status.ok()) {
      return trainer->ReportToRanks(status);
    }
  }
  return trainer;
}

absl::Status Trainer::PrepareState() {
  if (absl::Status status = BuildNetworks(*servers_->spec()); !status.ok()) return status;
  if (config_.resume && writes_run_dir()) {  // the other ranks get rank 0's state below
    const std::string checkpoint = config_.run_dir + "/checkpoint.pt";
    if (absl::Status status = LoadCheckpoint(checkpoint); !status.ok()) return status;
    LogLine("resumed %s at iteration %d (%lld env steps)", checkpoint, iteration_, static_cast<long long>(env_steps_));
  }
  return data_parallel_ ? ShareStartState() : absl::OkStatus();
}

uint64_t Trainer::rank_seed() const {
  return config_.seed + 1000003ull * static_cast<uint64_t>(config_.data_parallel.rank);
}

ServerPoolOptions Trainer::PoolOptions() const {
  const TrainerConfig& config = config_;
  ServerPoolOptions pool;
  pool.servers = config.servers;
  pool.token = config.token;
  pool.tls_ca_file = config.tls_ca_file;
  pool.envs_per_server = config.envs_per_server;
  pool.sessions_per_server = config.sessions_per_server;
  pool.session.set_part_layout(config.part_layout);
  for (const std::string& clip : config.motions) pool.session.add_motions(clip);
  pool.session.set_termination(v1::TRAINING);
  pool.session.set_action_mode(ToWire(ActionModeOf(config)));
  if (ActionModeOf(config) == ActionMode::kResidual) pool.session.set_residual_scale(static_cast<float>(config.residual_scale));
  // The curriculum's starting distance; every action message then carries the current one.
  pool.session.set_termination_distance(static_cast<float>(curriculum_.distance()));
  pool.session.set_termination_bodies(ToWire(TerminationBodiesOf(config)));
  pool.session.set_amp_obs(v1::FULL);
  pool.session.set_loop_clips(config.loop_clips);
  pool.session.set_anchor_reference(config.anchor_reference);
  pool.session.set_anchor_position_only(config.anchor_position_only);
  pool.session.set_reference_frames(config.reference_frames);
  for (const std::string& part : config.reward_parts) pool.session.add_reward_parts(part);
  pool.session.set_reward_relative_to_root(config.reward_relative_to_root);
  if (config.energy_weight != 1.0) pool.session.set_energy_weight(static_cast<float>(config.energy_weight));
  if (config.imitation_kernels.any()) {
    v1::ImitationKernels* kernels = pool.session.mutable_imitation_kernels();
    kernels->set_pos(static_cast<float>(config.imitation_kernels.pos));
    kernels->set_rot(static_cast<float>(config.imitation_kernels.rot));
    kernels->set_vel(static_cast<float>(config.imitation_kernels.vel));
    kernels->set_ang_vel(static_cast<float>(config.imitation_kernels.ang_vel));
  }
  if (!IsTrackingTask(config.task)) {
    pool.session.set_task(config.task);
    WriteTaskSettings(config, pool.session.mutable_task_settings());
  }
  return pool;
}

absl::Status Trainer::WaitForServers() {
  const absl::Time start = absl::Now();
  bool announced = false;
  while (true) {
    if (servers_->Reconnect(static_cast<int64_t>(rank_seed()) + iteration_) > 0) return absl::OkStatus();
    if (absl::Status refused = servers_->RefusedEverywhere(); !refused.ok()) return refused;
    const absl::Duration waited = absl::Now() - start;
    if (waited > absl::Seconds(config_.server_timeout_s)) {
      std::string tried;
      for (const auto& slot : servers_->slots()) {
        if (!slot->retired) absl::StrAppend(&tried, "\n  ", slot->server, ": ", slot->last_error);
      }
      for (const std::string& problem : servers_->discovery_problems()) absl::StrAppend(&tried, "\n  ", problem);
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

bool Trainer::ReadResumeArchive() {
  if (resume_archive_) return true;
  const std::string path = config_.run_dir + "/checkpoint.pt";
  auto bytes = ReadFileToString(path, kMaxCheckpointBytes);
  auto archive = bytes.ok() ? LoadCheckpointArchive(*bytes, path) : bytes.status();
  if (!archive.ok()) return false;
  resume_archive_ = *std::move(archive);
  return true;
}

void Trainer::ChooseReferenceFrames() {
  if (!config_.resume || config_.reference_frames_given || !writes_run_dir() || data_parallel_) return;
  if (!ReadResumeArchive()) return;
  torch::Tensor stored = torch::tensor(int64_t{1});
  resume_archive_->try_read("reference_frames", stored);
  config_.reference_frames = static_cast<int>(stored.item<int64_t>());
}

absl::Status Trainer::ChooseAmpFrames() {
  // A run resumed without --amp_frames reads what its checkpoint's discriminator read, so that
  // checkpoints from before the flag (the whole history) and from a preset with fewer frames resume.
  if (config_.resume && !config_.amp_frames_given && writes_run_dir() && !data_parallel_ &&
      layout_.amp_obs_per_frame > 0 && ReadResumeArchive()) {
    const absl::StatusOr<int64_t> stored = CheckpointAmpObsSize(*resume_archive_, config_.run_dir + "/checkpoint.pt");
    if (stored.ok() && *stored % layout_.amp_obs_per_frame == 0) {
      config_.model.amp_frames = *stored / layout_.amp_obs_per_frame;
    }
  }
  return ReadAmpFrames(config_.model.amp_frames, &layout_);
}

absl::Status Trainer::BuildNetworks(const v1::EnvSpec& spec) {
  spec_ = spec;
  layout_ = LayoutFromWireSpec(spec);
  if (absl::Status status = layout_.Validate(); !status.ok()) {
    return absl::FailedPreconditionError(absl::StrCat("server env spec: ", status.message()));
  }
  if (layout_.task != config_.task) {
    return absl::FailedPreconditionError(absl::StrCat("--task ", config_.task, ": the server opened a ", layout_.task,
                                                      " session (a server without task envs?)"));
  }
  if (absl::Status status = ChooseAmpFrames(); !status.ok()) return status;
  if (skills_) {
    if (absl::Status status = skills_->CheckFits(tracking_spec_, spec); !status.ok()) return status;
    config_.model = skills_->ConfigFor(config_.model);
  }
  policy_ = ModSkillPolicy(layout_, config_.model);
  critic_ = Critic(layout_.obs_size, config_.model.critic_hidden, config_.normalize_value);
  discriminator_ = AmpDiscriminator(layout_.amp_obs_size, config_.model.discriminator_hidden);
  obs_norm_ = RunningMeanStd(layout_.obs_size);
  amp_norm_ = RunningMeanStd(layout_.amp_obs_size);
  if (!config_.init_from.empty()) {
    ActionMapping action;
    action.mode = ParseActionMode(config_.action_mode).value_or(ActionMode::kResidual);
    action.residual_scale = config_.residual_scale;
    auto tracker = LoadTrackerForRetraining(config_.init_from, config_.train_parts, spec.part_layout(), layout_, action,
                                            config_.train_attention, config_.fresh_parts);
    if (!tracker.ok()) return tracker.status();
    policy_ = tracker->policy;
    obs_norm_ = tracker->obs_norm;
    config_.model = config_.model.WithPolicyShapeOf(policy_->config());  // config.json and the checkpoint record it
    if (config_.frozen_parts_act_on_mean) {
      // The frozen parts act as they do in evaluation, so their noise does not blur the
      // retrained parts' returns; their dims then leave PPO's ratios.
      sampled_dims_ = torch::zeros({layout_.action_size});
      for (int p : tracker->trained_parts) {
        sampled_dims_.slice(0, layout_.parts[p].action_start, layout_.parts[p].action_start + layout_.parts[p].action_size)
            .fill_(1.f);
      }
    }
    LogLine("init from %s: %d of %d parts train%s", config_.init_from, static_cast<int>(tracker->trained_parts.size()),
            static_cast<int>(layout_.parts.size()),
            config_.train_parts.empty() ? "" : " (the others and the observation statistics are frozen)");
  }
  if (skills_) {
    if (absl::Status status = LoadSkills(); !status.ok()) return status;
  }
  // The skills' controllers are frozen: only what requires gradients is trained.
  BuildPolicyOptimizer();
  discriminator_optimizer_ = std::make_unique<torch::optim::Adam>(
      discriminator_->parameters(), torch::optim::AdamOptions(config_.discriminator_learning_rate));
  return absl::OkStatus();
}

void Trainer::BuildPolicyOptimizer() {
  optimizer_ = std::make_unique<torch::optim::Adam>(
      TrainableParameterGroups(*policy_, *critic_, config_.learning_rate, config_.critic_learning_rate),
      torch::optim::AdamOptions(config_.learning_rate));
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
    // Data-parallel ranks stop together: a signal or a time budget on one stops them all.
    const absl::StatusOr<bool> stopping = AnyRankStops(stop != nullptr && stop->load());
    if (!stopping.ok()) return ReportToRanks(stopping.status());
    if (*stopping) break;
    absl::StatusOr<IterationStats> stats;
    try {
      torch::AutoGradMode grad(true);  // whatever the caller's mode, the update needs gradients
      stats = Iterate();
    } catch (const std::exception& e) {
      std::string message = e.what();
      return ReportToRanks(
          absl::InternalError(absl::StrCat("iteration ", iteration_ + 1, ": ", message.substr(0, message.find('\n')))));
    }
    if (!stats.ok()) return ReportToRanks(stats.status());
    history_.push_back(*stats);
    if (on_iteration) on_iteration(*stats);
    if (writes_run_dir() && (iteration_ % config_.checkpoint_every == 0 || iteration_ == last)) {
      if (absl::Status status = SaveCheckpoint(config_.run_dir + "/checkpoint.pt"); !status.ok()) return status;
      if (absl::Status status = ExportPolicy(config_.run_dir + "/policy.pt"); !status.ok()) return status;
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<IterationStats> Trainer::Iterate() {
  IterationStats stats;
  const auto start = Clock::now();
  const double collective_seconds = data_parallel_ ? data_parallel_->collective_seconds() : 0;
  const int64_t collective_bytes = data_parallel_ ? data_parallel_->collective_bytes() : 0;
  Collection collection;
  if (pending_.valid()) {
    collection = std::move(*pending_.get());  // collected while the last update ran
  } else {
    servers_->Reconnect(static_cast<int64_t>(rank_seed()) + iteration_ + 1);
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
  if (data_parallel_) data_parallel_->MarkIteration(iteration_);
  const absl::StatusOr<bool> every_rank_has_experience = OnEveryRank(!usable.empty());
  if (!every_rank_has_experience.ok()) return every_rank_has_experience.status();
  if (!*every_rank_has_experience) {
    // Every server (of a rank) failed during this iteration: nothing to learn from; try again.
    stats.iteration = iteration_;
    stats.env_steps = env_steps_;
    LogLine("iteration %d: every session failed while collecting; retrying", iteration_ + 1);
    return stats;
  }
  if (absl::Status status = SummarizeEpisodes(&stats); !status.ok()) return status;
  SummarizeTaskEpisodes(collection, &stats);
  const ScopedTorchThreads threads(UpdateThreads());  // the servers wait from here on
  TrainingBatch batch = ComputeReturns(usable);
  if (stats.policy_lag > 0) CenterOnCurrentPolicy(&batch);
  const torch::Tensor expert =
      config_.amp_reward_weight > 0 ? FetchReferenceAmp(usable.front()->slot) : torch::Tensor();
  // Failures of episodes that do not follow clips mean nothing to the servers' clip samplers.
  if (config_.report_every > 0 && (iteration_ + 1) % config_.report_every == 0 && TaskFollowsClips(config_.task)) {
    ReportFailures();
  }
  if (config_.collect_during_update) {
    servers_->Reconnect(static_cast<int64_t>(rank_seed()) + iteration_ + 2);
    if (!servers_->Alive().empty()) StartCollection();
  }
  const auto update_start = Clock::now();
  if (absl::Status status = UpdatePolicy(batch, &stats); !status.ok()) return status;
  ++policy_version_;
  if (expert.defined()) {
    if (absl::Status status = UpdateDiscriminator(batch, expert, &stats); !status.ok()) return status;
  }
  std::vector<double> samples = {batch.samples};  // every rank's, in data-parallel runs
  if (absl::Status status = SumOverRanks(&samples); !status.ok()) return status;
  ++iteration_;
  env_steps_ += static_cast<int64_t>(samples[0]);
  stats.update_seconds = std::chrono::duration<double>(Clock::now() - update_start).count();
  stats.env_steps_per_second = samples[0] / std::chrono::duration<double>(Clock::now() - start).count();
  if (data_parallel_) {
    stats.allreduce_seconds = data_parallel_->collective_seconds() - collective_seconds;
    stats.allreduce_bytes = data_parallel_->collective_bytes() - collective_bytes;
  }
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
    snapshot_.critic = Critic(layout_.obs_size, config_.model.critic_hidden, config_.normalize_value);
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

void Trainer::Summarize(const TrainingBatch& batch, IterationStats* stats) {
  stats->iteration = iteration_;
  stats->env_steps = env_steps_;
  stats->mean_task_reward = batch.task_sum / batch.samples;
  stats->mean_amp_reward = batch.amp_sum / batch.samples;
  const int64_t terms = std::min<int64_t>(batch.terms_sum.size(0), 8);
  for (int64_t k = 0; k < terms; ++k) stats->reward_terms[k] = batch.terms_sum[k].item<double>() / batch.samples;
  stats->live_sessions = batch.live_sessions;
}

absl::Status Trainer::SummarizeEpisodes(IterationStats* stats) {
  // Episodes, and the sums of their returns, lengths and tracked flags: every rank's, so that
  // the curriculum moves alike on every rank.
  std::vector<double> sums = {static_cast<double>(recent_returns_.size()), 0, 0, 0};
  for (size_t i = 0; i < recent_returns_.size(); ++i) {
    sums[1] += recent_returns_[i];
    sums[2] += recent_lengths_[i];
    sums[3] += recent_tracked_[i];
  }
  if (absl::Status status = SumOverRanks(&sums); !status.ok()) return status;
  if (sums[0] > 0) {
    stats->mean_episode_return = sums[1] / sums[0];
    stats->mean_episode_length = sums[2] / sums[0];
    stats->tracked_share = sums[3] / sums[0];
    curriculum_.Update(stats->tracked_share);
  }
  return absl::OkStatus();
}

}  // namespace modskill::learner
