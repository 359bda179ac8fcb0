// The trainer as one rank of data-parallel learners (data_parallel.h): what the ranks check at
// startup, the state rank 0 gives them, and the few agreements an iteration needs so that every
// rank takes the same steps. Alone (world size 1) each of these is a no-op without a collective.
#include <string>
#include <vector>

#include <ATen/Parallel.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "common/log.h"
#include "learner/trainer.h"

namespace modskill::learner {
namespace {

// Values as text, doubles to the last bit (StrCat keeps 6 digits).
std::string Text(double value) { return absl::StrFormat("%.17g", value); }
std::string Text(int64_t value) { return absl::StrCat(value); }
std::string Text(int value) { return absl::StrCat(value); }
std::string Text(uint64_t value) { return absl::StrCat(value); }
std::string Text(bool value) { return value ? "true" : "false"; }
std::string Text(const std::vector<int64_t>& sizes) { return absl::StrJoin(sizes, ","); }

// What changes the tensors' shapes or the update's arithmetic, by flag name. The servers, their
// envs and sessions, the clips, the token and the run directory are each rank's own.
std::vector<SharedSetting> SharedSettings(const TrainerConfig& c) {
  const ModelConfig& m = c.model;
  return {
      {"world_size", Text(c.data_parallel.world_size)},
      {"preset", m.preset},
      {"part_layout", c.part_layout},
      {"whole_body", Text(m.whole_body)},
      {"no_attention", Text(!m.attention)},
      {"controller_input", ControllerInputName(m.controller_input)},
      {"preset (attention, controller, critic, discriminator sizes)",
       absl::StrCat(Text(m.attention_hidden), "/", Text(m.embed_dim), "/", Text(m.controller_hidden), "/",
                    Text(m.critic_hidden), "/", Text(m.discriminator_hidden))},
      {"log_std", Text(m.log_std)},
      {"task", c.task},
      {"task_hidden", Text(m.task_hidden)},
      {"task_log_std", Text(m.task_log_std)},
      {"task_skill_prior", Text(m.task_skill_prior)},
      {"task_parts", absl::StrJoin(c.task_parts, ",")},
      {"task_teacher", absl::StrCat(c.task_teacher, " ", Text(c.task_teacher_weight), " ", Text(c.task_teacher_steps))},
      {"action_mode", c.action_mode},
      {"residual_scale", Text(c.residual_scale)},
      {"termination_distance", Text(c.termination_distance)},
      {"termination_bodies", c.termination_bodies},
      {"termination_curriculum", absl::StrCat(Text(c.curriculum_start), ":", Text(c.curriculum_end))},
      {"loop_clips", Text(c.loop_clips)},
      {"anchor_reference", Text(c.anchor_reference)},
      {"anchor_position_only", Text(c.anchor_position_only)},
      {"reference_frames", absl::StrCat(c.reference_frames)},
      {"reward_parts", absl::StrJoin(c.reward_parts, ",")},
      {"reward_relative_to_root", Text(c.reward_relative_to_root)},
      {"frozen_parts_act_on_mean", Text(c.frozen_parts_act_on_mean)},
      {"fresh_parts", Text(c.fresh_parts)},
      {"iterations", Text(c.iterations)},
      {"horizon", Text(c.horizon)},
      {"epochs", Text(c.epochs)},
      {"minibatch_size", Text(c.minibatch_size)},
      {"learning_rate", Text(c.learning_rate)},
      {"learning_rate_decay_steps", Text(c.learning_rate_decay_steps)},
      {"learning_rate_floor", Text(c.learning_rate_floor)},
      {"critic_learning_rate", Text(c.critic_learning_rate)},
      {"gamma", Text(c.gamma)},
      {"lambda", Text(c.lambda)},
      {"clip_ratio", Text(c.clip_ratio)},
      {"value_clip", Text(c.value_clip)},
      {"value_coefficient", Text(c.value_coefficient)},
      {"max_grad_norm", Text(c.max_grad_norm)},
      {"amp_reward_weight", absl::StrCat(Text(c.amp_reward_weight), " (task ", Text(c.task_reward_weight), ")")},
      {"energy_weight", Text(c.energy_weight)},
      {"imitation_kernels", ImitationKernelsText(c.imitation_kernels)},
      {"noise_hold_steps", Text(c.noise_hold_steps)},
      {"discriminator_learning_rate", Text(c.discriminator_learning_rate)},
      {"gradient_penalty_weight", Text(c.gradient_penalty_weight)},
      {"discriminator_epochs", Text(c.discriminator_epochs)},
      {"amp_samples", Text(c.amp_samples)},
      {"amp_frames", Text(m.amp_frames)},
      {"seed", Text(c.seed)},
      {"report_every", Text(c.report_every)},
      {"checkpoint_every", Text(c.checkpoint_every)},
      {"resume", Text(c.resume)},
      {"collect_during_update", Text(c.collect_during_update)},
      // Torch's thread count changes the order of the gradient norm's sums, hence its last bits.
      {"update_threads", Text(c.update_threads)},
      {"threads", Text(at::get_num_threads())},
  };
}

}  // namespace

absl::Status Trainer::JoinRanks() {
  const DataParallelOptions& options = config_.data_parallel;
  LogLine("rank %d of %d: joining at --rendezvous %s (up to %.0f s)", options.rank, options.world_size,
          options.rendezvous, options.rendezvous_timeout_s);
  absl::StatusOr<std::unique_ptr<DataParallel>> group = DataParallel::Join(options);
  if (!group.ok()) return group.status();
  data_parallel_ = *std::move(group);
  return data_parallel_->CheckSettingsAgree("settings", SharedSettings(config_), options.rendezvous_timeout_s);
}

absl::Status Trainer::ShareStartState() {
  // Ranks get here once their servers answer: allow for that wait as well.
  const double wait_s = config_.data_parallel.rendezvous_timeout_s + config_.server_timeout_s;
  int64_t parameters = 0;
  for (const torch::Tensor& p : policy_->parameters()) parameters += p.numel();
  const std::vector<SharedSetting> layout = {
      {"task (server session)", layout_.task},
      {"observation size (server)", Text(layout_.obs_size)},
      {"action size (server)", Text(layout_.action_size)},
      {"AMP observation size (server)", Text(layout_.amp_obs_size)},
      {"policy parameters (--skills, --preset)", Text(parameters)},
  };
  if (absl::Status status = data_parallel_->CheckSettingsAgree("layout", layout, wait_s); !status.ok()) return status;
  std::string state;
  if (data_parallel_->rank() == 0) {
    absl::StatusOr<std::string> mine = SerializeState();
    if (!mine.ok()) return mine.status();
    state = *std::move(mine);
  }
  if (absl::Status status = data_parallel_->Broadcast(&state); !status.ok()) return status;
  if (data_parallel_->rank() != 0) {
    if (absl::Status status = RestoreState(state, "rank 0's training state"); !status.ok()) return status;
  }
  LogLine("rank %d of %d: started from rank 0's state at iteration %d (%lld bytes)", data_parallel_->rank(),
          data_parallel_->world_size(), iteration_, static_cast<long long>(state.size()));
  return absl::OkStatus();
}

GradientAverager Trainer::Averager() {
  if (!data_parallel_) return nullptr;
  return [group = data_parallel_.get()](const std::vector<torch::Tensor>& params, bool finite) {
    return group->AverageGradients(params, finite);
  };
}

absl::StatusOr<bool> Trainer::OnEveryRank(bool mine) {
  if (!data_parallel_) return mine;
  absl::StatusOr<double> least = data_parallel_->AllReduceMin(mine ? 1 : 0);
  if (!least.ok()) return least.status();
  return *least > 0.5;
}

absl::Status Trainer::SumOverRanks(std::vector<double>* values) {
  return data_parallel_ ? data_parallel_->AllReduceSum(values) : absl::OkStatus();
}

absl::Status Trainer::UpdateStats(RunningMeanStdImpl& stats, const torch::Tensor& batch) {
  if (data_parallel_) return data_parallel_->MergeRunningStats(stats, batch);
  stats.Update(batch);
  return absl::OkStatus();
}

absl::StatusOr<bool> Trainer::AnyRankStops(bool stop) {
  if (!data_parallel_) return stop;
  absl::StatusOr<bool> every_rank_goes_on = OnEveryRank(!stop);
  if (!every_rank_goes_on.ok()) return every_rank_goes_on.status();
  return !*every_rank_goes_on;
}

absl::Status Trainer::ReportToRanks(absl::Status status) {
  if (data_parallel_ && !status.ok()) data_parallel_->ReportFailure(status);
  return status;
}

}  // namespace modskill::learner
