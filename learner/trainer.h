// ModSkill training: part-level PPO with an AMP discriminator, driving one or many simulation
// servers over gRPC (docs/DESIGN.md section 3). The learner runs inference for every env it drives
// (central inference) and overlaps each session's simulation with the other sessions' inference.
#ifndef MODSKILL_LEARNER_TRAINER_H_
#define MODSKILL_LEARNER_TRAINER_H_

#include <atomic>
#include <functional>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <torch/torch.h>

#include "absl/status/status.h"
#include "learner/acting_networks.h"
#include "learner/amp_discriminator.h"
#include "learner/critic.h"
#include "learner/data_parallel.h"
#include "learner/episode_ends.h"
#include "learner/held_noise.h"
#include "learner/modskill_policy.h"
#include "learner/ppo_update.h"
#include "learner/reach_teacher.h"
#include "learner/running_mean_std.h"
#include "learner/server_pool.h"
#include "learner/skill_library.h"
#include "learner/task_return.h"
#include "learner/termination_curriculum.h"
#include "learner/trainer_config.h"

namespace modskill::learner {

// What one iteration measured; also written to TensorBoard and the CSV.
struct IterationStats {
  int iteration = 0;
  int64_t env_steps = 0;          // total so far
  double collect_seconds = 0;
  double update_seconds = 0;
  double env_steps_per_second = 0;  // this iteration, collection and update included
  double mean_task_reward = 0;    // per step: the server's reward (its terms' sum)
  double mean_amp_reward = 0;
  double mean_episode_return = 0;  // task reward, episodes completed recently
  double mean_episode_length = 0;
  double reward_terms[8] = {};
  double learning_rate = 0;  // the policy's (and the critic's) step size of this iteration's update
  double critic_learning_rate = 0;  // with --critic_learning_rate: the critic's, else 0
  double policy_loss = 0, value_loss = 0, approx_kl = 0, clip_fraction = 0;
  double teacher_weight = 0, teacher_loss = 0;  // --task_teacher: this update's weight, its unweighted loss
  double discriminator_loss = 0, expert_logit = 0, policy_logit = 0, gradient_penalty = 0;
  int live_sessions = 0;
  int skipped_updates = 0;  // minibatches skipped for a non-finite loss
  double termination_distance = 0;  // m, the distance this iteration's episodes ran under
  double tracked_share = 0;         // recently ended episodes that reached their clip's end
  // Policy updates between the weights that collected this iteration's batch and the weights it
  // updates: 0, or 1 when collection runs during the update (config.collect_during_update).
  int policy_lag = 0;
  // Task runs: the mean normalized return (task_return.h) of the episodes that ended during this
  // iteration's collection; NaN when none ended (and in tracking runs).
  double normalized_return = std::numeric_limits<double>::quiet_NaN();
  int task_episodes = 0;  // those episodes
  EpisodeEnds task_ends;  // why they ended
  // Data-parallel runs: this rank's time in, and bytes sent into, collectives this iteration.
  double allreduce_seconds = 0;
  int64_t allreduce_bytes = 0;
};

// The largest trainer checkpoint a resume reads (the paper preset's networks with Adam's moments
// are a few hundred MB).
inline constexpr size_t kMaxCheckpointBytes = size_t{4} << 30;

// A trainer checkpoint's bytes, deserialized (`origin` names them in errors).
absl::StatusOr<std::unique_ptr<torch::serialize::InputArchive>> LoadCheckpointArchive(const std::string& checkpoint_bytes,
                                                                                      const std::string& origin);
// The AMP observation size a trainer checkpoint's discriminator was trained on.
absl::StatusOr<int64_t> CheckpointAmpObsSize(torch::serialize::InputArchive& checkpoint, const std::string& origin);

class Trainer {
 public:
  static absl::StatusOr<std::unique_ptr<Trainer>> Create(const TrainerConfig& config);
  ~Trainer();

  // Runs config.iterations iterations (after those of a resumed run). `on_iteration` sees each
  // iteration's figures. Returns when done, when `stop` becomes true, or on a fatal error.
  absl::Status Run(const std::function<void(const IterationStats&)>& on_iteration = nullptr,
                   const std::atomic<bool>* stop = nullptr);

  int iteration() const { return iteration_; }
  int64_t env_steps() const { return env_steps_; }
  // The training termination distance the next iteration runs under (m).
  double termination_distance() const { return curriculum_.distance(); }
  const std::vector<IterationStats>& history() const { return history_; }
  ModSkillPolicy& policy() { return policy_; }
  Critic& critic() { return critic_; }
  AmpDiscriminator& discriminator() { return discriminator_; }
  RunningMeanStd& obs_norm() { return obs_norm_; }
  RunningMeanStd& amp_norm() { return amp_norm_; }
  // Whether this learner writes the run's files: rank 0 of a data-parallel group, or alone.
  bool writes_run_dir() const { return config_.data_parallel.rank == 0; }
  ServerPool& servers() { return *servers_; }
  // The sessions' env spec (the task session's in a task run), and the config as the run uses it
  // (a task run takes its controller sizes and action mapping from the skills).
  const v1::EnvSpec& spec() const { return spec_; }
  const TrainerConfig& config() const { return config_; }

  // Full training state (networks, optimizers, normalizers, counters), written atomically.
  absl::Status SaveCheckpoint(const std::string& path);
  // Reads `path`, or takes the archive ChooseAmpFrames already loaded from it.
  absl::Status LoadCheckpoint(const std::string& path);
  // The same state as bytes, and restored from bytes or a loaded archive (`origin` names them in errors).
  absl::StatusOr<std::string> SerializeState();
  absl::Status RestoreState(const std::string& bytes, const std::string& origin);
  absl::Status RestoreState(torch::serialize::InputArchive& archive, const std::string& origin);
  // The TorchScript policy the server's Rollout and Python's torch.jit.load run.
  absl::Status ExportPolicy(const std::string& path);

 private:
  explicit Trainer(const TrainerConfig& config);
  // The sessions every server opens (config_'s task, layout, action mapping, termination).
  ServerPoolOptions PoolOptions() const;
  absl::Status WaitForServers();
  absl::Status BuildNetworks(const v1::EnvSpec& spec);
  // How many of the server's AMP frames the discriminator reads (--amp_frames, or on resume the
  // checkpoint's), set in layout_.amp_obs_size.
  absl::Status ChooseAmpFrames();
  // A run resumed without --reference_frames observes as many frames as its checkpoint's policy
  // (one for checkpoints from before the flag), so a preset's default cannot change it midway.
  void ChooseReferenceFrames();
  // The resumed run's checkpoint, deserialized once into resume_archive_; false (LoadCheckpoint
  // reports why) when it cannot be read.
  bool ReadResumeArchive();
  // Networks, then the resumed checkpoint (rank 0), then the start state shared by every rank.
  absl::Status PrepareState();
  // Seeds of what must differ between data-parallel ranks (sessions, action noise, reference
  // samples): config.seed on rank 0 and alone.
  uint64_t rank_seed() const;

  // Data-parallel learners (trainer_data_parallel.cc). Joins the group and checks that the ranks'
  // settings agree, before any server is contacted.
  absl::Status JoinRanks();
  // Once the networks are built (and rank 0 resumed): the ranks' layouts agree and rank 0's whole
  // state (weights, optimizers, normalizers, counters) replaces every other rank's.
  absl::Status ShareStartState();
  // The averaged-gradient hook of the PPO and discriminator updates (null when alone).
  GradientAverager Averager();
  // Whether `mine` holds on every rank (alone: `mine`).
  absl::StatusOr<bool> OnEveryRank(bool mine);
  // Sums `values` over the ranks (alone: unchanged).
  absl::Status SumOverRanks(std::vector<double>* values);
  // Merges `batch` into `stats`: over every rank's batch when data-parallel.
  absl::Status UpdateStats(RunningMeanStdImpl& stats, const torch::Tensor& batch);
  // Whether any rank was asked to stop (alone: `stop`).
  absl::StatusOr<bool> AnyRankStops(bool stop);
  // `status`, after posting it for the other ranks to name.
  absl::Status ReportToRanks(absl::Status status);
  // A task run (trainer_task.cc), before any session opens: loads the skills (errors name the
  // file), takes their action mapping, and checks that the first server offers config_.task
  // (INVALID_ARGUMENT naming --task otherwise), keeping its tracking spec.
  absl::Status PrepareTask();
  // A task run's networks once the session's spec is known: the skills must fit it; the policy
  // gets their frozen controllers and the normalizer their statistics of the self features.
  absl::Status LoadSkills();
  // One PPO iteration, in the phases of the algorithm box: collect, returns, policy update,
  // discriminator update, summary. With config.collect_during_update the next iteration's
  // collection runs on its own thread, with the weights from before the update, while the update runs.
  absl::StatusOr<IterationStats> Iterate();
  struct SlotRollout;
  struct TrainingBatch;
  struct Collection;
  // Steps every live session `horizon` times with `acting` (round robin: while one session's
  // server steps, the learner computes another's actions).
  Collection Collect(ActingNetworks acting);
  // Samples actions for `obs` into step t of `r` and sends them.
  absl::Status Act(SlotRollout& r, int t, const torch::Tensor& obs, ActingNetworks& acting);
  // Books one step result of `r` (rewards, dones, episode ends) at step t.
  absl::Status RecordStep(SlotRollout& r, int t);
  // Torch threads for the update phases (0: keep the current number).
  int UpdateThreads() const;
  // The networks being trained, for a collection that waits for its update.
  ActingNetworks LiveNetworks();
  // Starts collecting the next batch on its own thread with a copy of the current weights.
  void StartCollection();
  // Waits for a collection started by StartCollection and drops it (end of a run).
  void DiscardCollection();
  // AMP rewards, then GAE per session; concatenates the sessions' experience.
  TrainingBatch ComputeReturns(const std::vector<SlotRollout*>& usable);
  // A batch collected by older weights: PPO's clipping is centred on the current weights and the
  // advantages importance-weighted toward them (decoupled PPO, ppo_loss.h).
  void CenterOnCurrentPolicy(TrainingBatch* batch);
  // amp_samples x discriminator_epochs random rows of `amp_rows` (one tensor per session) among
  // its `live_rows` (indices of rows whose episode did not end).
  torch::Tensor SampleLiveAmp(const std::vector<torch::Tensor>& amp_rows, const std::vector<torch::Tensor>& live_rows);
  absl::Status UpdatePolicy(const TrainingBatch& batch, IterationStats* stats);
  // amp_samples reference AMP observations from `source`'s server ([0, M] when it cannot answer).
  torch::Tensor FetchReferenceAmp(SessionSlot* source);
  // The discriminator: `expert` (reference) samples against the policy's own.
  absl::Status UpdateDiscriminator(const TrainingBatch& batch, const torch::Tensor& expert, IterationStats* stats);
  // Episode figures of the recently ended episodes (every rank's); moves the termination curriculum.
  absl::Status SummarizeEpisodes(IterationStats* stats);
  void Summarize(const TrainingBatch& batch, IterationStats* stats);
  // Notes how the episodes that ended in `result` went, for the session's failure report;
  // `done` and `truncated` are the result's flags as RecordStep decoded them (one per env),
  // `ended_lengths` the control steps of each episode that ended.
  absl::Status RecordEpisodeEnds(SessionSlot* slot, const v1::StepResult& result, const float* done,
                                 const float* truncated, const std::vector<int>& ended_lengths);
  // Sends each live session its failure list and logs the hardest clips.
  void ReportFailures();
  // Task runs: the normalized return of the episodes that ended in `collection`.
  void SummarizeTaskEpisodes(const Collection& collection, IterationStats* stats) const;

  TrainerConfig config_;
  std::unique_ptr<DataParallel> data_parallel_;  // null when alone
  std::unique_ptr<ServerPool> servers_;
  v1::EnvSpec spec_;
  NetworkLayout layout_;
  // Task runs: the reused skills, Describe's tracking spec of the part layout (where the skills'
  // features sit in a tracker's observation), and the episode figure.
  std::optional<SkillLibrary> skills_;
  v1::EnvSpec tracking_spec_;
  std::optional<TaskReturn> task_return_;
  // The checkpoint a resume starts from, read and deserialized once for ChooseAmpFrames and LoadCheckpoint.
  std::unique_ptr<torch::serialize::InputArchive> resume_archive_;
  ModSkillPolicy policy_{nullptr};
  Critic critic_{nullptr};
  AmpDiscriminator discriminator_{nullptr};
  RunningMeanStd obs_norm_{nullptr};
  RunningMeanStd amp_norm_{nullptr};
  // Adam over the trainable policy and the critic: one group, or two with critic_learning_rate.
  void BuildPolicyOptimizer();
  // RestoreState's parts: the refusal of a checkpoint another kind of run trained, the critic's
  // step size (the checkpoint's, unless --critic_learning_rate is given), and the returns'
  // discount and GAE lambda (the checkpoint's, unless --gamma / --lambda are given).
  absl::Status CheckCheckpointMatchesRun(torch::serialize::InputArchive& archive, const std::string& path);
  absl::Status RestoreCriticLearningRate(torch::serialize::InputArchive& archive, const std::string& path);
  void RestoreReturnSettings(torch::serialize::InputArchive& archive, const std::string& path);
  std::unique_ptr<torch::optim::Adam> optimizer_;
  std::unique_ptr<torch::optim::Adam> discriminator_optimizer_;
  int iteration_ = 0;
  int64_t env_steps_ = 0;
  std::vector<IterationStats> history_;
  // Episode bookkeeping per env slot of each session.
  std::vector<std::vector<double>> episode_return_;
  std::vector<std::vector<int>> episode_length_;
  std::vector<std::vector<double>> episode_goal_return_;  // task runs: TaskReturn::GoalReward summed
  std::vector<double> recent_returns_, recent_lengths_;
  std::vector<double> recent_tracked_;  // 1 where a recent episode reached its clip's end
  TerminationCurriculum curriculum_{0.25, 0.25};
  std::unordered_map<SessionSlot*, size_t> slot_index_;  // into episode_return_ / episode_length_
  torch::Generator generator_;         // minibatches and AMP draws (the update's thread)
  torch::Generator acting_generator_;  // action noise (the collection's thread)
  HeldNoise held_noise_;               // that noise, held per env (--noise_hold_steps)
  // PpoSettings::sampled_dims: with --frozen_parts_act_on_mean, 1 over the retrained parts' actions
  // and 0 over the frozen parts'; with --task_parts, 1 over those parts' z (task_parts.h);
  // undefined otherwise (every dim is sampled).
  torch::Tensor sampled_dims_;
  std::optional<ReachTeacher> teacher_;  // --task_teacher
  torch::Tensor teacher_parts_;          // its supervised parts, [P]
  int64_t policy_version_ = 0;         // policy updates so far
  ActingNetworks snapshot_;            // the weights a collection during the update acts with
  std::future<std::shared_ptr<Collection>> pending_;  // that collection
  // Failure lists not yet reported, per session (keyed by slot and its session generation).
  struct PendingReports {
    int64_t generation = -1;
    std::vector<v1::ClipFailure> failures;
  };
  std::map<SessionSlot*, PendingReports> pending_reports_;
  // Per clip over the whole run: failures and successes, for the log of hardest clips.
  std::map<std::string, std::pair<int64_t, int64_t>> clip_outcomes_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TRAINER_H_
