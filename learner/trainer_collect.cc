// The collection phase: every live session steps T times under the acting weights; results are
// checked, recorded and turned into failure reports for the server's samplers.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/functional/function_ref.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/log.h"
#include "common/wire/tensor_codec.h"
#include "learner/policy_export.h"
#include "learner/trainer.h"
#include "learner/trainer_phases.h"
#include "learner/wire_torch.h"

namespace modskill::learner {

Trainer::Collection Trainer::Collect(ActingNetworks acting) {
  const int T = config_.horizon;
  const int64_t O = layout_.obs_size, S = acting.policy->sample_size(), M = layout_.amp_obs_size;
  Collection collection;
  collection.termination_distance = curriculum_.distance();
  collection.policy_version = acting.version;
  std::vector<SlotRollout>& rollouts = collection.rollouts;
  for (SessionSlot* slot : servers_->Alive()) {
    SlotRollout r;
    r.slot = slot;
    r.n = slot->num_envs();
    r.obs = torch::zeros({T, r.n, O});
    r.actions = torch::zeros({T, r.n, S});
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
    episode_goal_return_.resize(servers_->slots().size());
  }
  for (SlotRollout& r : rollouts) {
    auto& returns = episode_return_[slot_index_[r.slot]];
    auto& lengths = episode_length_[slot_index_[r.slot]];
    if (returns.size() != static_cast<size_t>(r.n)) {
      returns.assign(r.n, 0.0);
      lengths.assign(r.n, 0);
      episode_goal_return_[slot_index_[r.slot]].assign(r.n, 0.0);
    }
    // Where the slot's envs are: the last result, or the first observation of a new session.
    const SimulationStream& stream = *r.slot->stream;
    const bool fresh = stream.opened().initial().step() == 0 && stream.result().obs().data().empty();
    const v1::StepResult& result = fresh ? stream.opened().initial() : stream.result();
    const absl::StatusOr<torch::Tensor> obs = WireToTorch(result.obs(), "StepResult.obs", v1::FLOAT32, {r.n, O});
    if (absl::Status status = obs.ok() ? Act(r, 0, *obs, acting) : obs.status(); !status.ok()) fail(r, status);
  }
  for (int t = 0; t < T; ++t) {
    for (SlotRollout& r : rollouts) {
      if (r.failed) continue;
      if (absl::Status status = r.slot->stream->ReceiveResult(); !status.ok()) {
        fail(r, status);
        continue;
      }
      const absl::StatusOr<torch::Tensor> next =
          WireToTorch(r.slot->stream->result().obs(), "StepResult.obs", v1::FLOAT32, {r.n, O});
      absl::Status status = next.ok() ? RecordStep(r, t) : next.status();
      if (status.ok() && t + 1 < T) status = Act(r, t + 1, *next, acting);
      if (!status.ok()) {
        fail(r, status);
      } else if (t + 1 == T) {
        r.next_obs = *next;
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
// would move log-probabilities by tens of nats.) PPO samples in the policy's sample space (the
// actions, or z in a task run); the server gets the actions of the sample.
absl::Status Trainer::Act(SlotRollout& r, int t, const torch::Tensor& obs, ActingNetworks& acting) {
  torch::NoGradGuard no_grad;
  const torch::Tensor normalized = acting.obs_norm->Normalize(obs);
  r.raw_obs.push_back(obs);
  const torch::Tensor mean = acting.policy->SampleMean(normalized);
  const torch::Tensor log_std = acting.policy->log_std();
  torch::Tensor noise =
      log_std.exp() * held_noise_.Next(slot_index_[r.slot], mean.size(0), mean.size(1), acting_generator_);
  if (sampled_dims_.defined()) noise *= sampled_dims_;
  const torch::Tensor sample = mean + noise;
  r.obs[t].copy_(normalized);
  r.actions[t].copy_(sample);
  r.log_prob[t].copy_(ModSkillPolicyImpl::LogProb(mean, log_std, sample, sampled_dims_));
  r.values[t].copy_(acting.critic->forward(normalized));
  const torch::Tensor contiguous = acting.policy->ActionsFor(normalized, sample).contiguous();
  return r.slot->stream->SendActions(contiguous.data_ptr<float>());
}

absl::Status Trainer::RecordStep(SlotRollout& r, int t) {
  const v1::StepResult& result = r.slot->stream->result();
  auto reward = WireToTorch(result.reward(), "StepResult.reward", v1::FLOAT32, {r.n});
  auto done = WireToTorch(result.done(), "StepResult.done", v1::UINT8, {r.n});
  auto truncated = WireToTorch(result.truncated(), "StepResult.truncated", v1::UINT8, {r.n});
  auto amp = WireToTorch(result.amp_obs(), "StepResult.amp_obs", v1::FLOAT32, {r.n, layout_.wire_amp_obs_size()});
  auto terms = WireToTorch(result.reward_terms(), "StepResult.reward_terms", v1::FLOAT32,
                           {r.n, spec_.reward_terms_size()});
  for (const auto* tensor : {&reward, &done, &truncated, &amp, &terms}) {
    if (!tensor->ok()) return tensor->status();
  }
  // Only task runs count why their episodes end.
  absl::StatusOr<std::vector<int>> causes = task_return_ ? ReadEndCauses(result, r.n) : std::vector<int>{};
  if (!causes.ok()) return causes.status();
  r.task_reward[t].copy_(*reward);
  r.dones[t].copy_(*done);
  held_noise_.EpisodesEnded(slot_index_[r.slot], *done);
  r.truncated[t].copy_(*truncated);
  r.amp_next[t].copy_(amp->narrow(1, 0, layout_.amp_obs_size));  // the newest frames: what the discriminator reads
  r.reward_terms_sum += terms->to(torch::kFloat64).sum(0);
  auto& returns = episode_return_[slot_index_[r.slot]];
  auto& lengths = episode_length_[slot_index_[r.slot]];
  auto& goal_returns = episode_goal_return_[slot_index_[r.slot]];
  const torch::Tensor goal_reward = task_return_ ? task_return_->GoalReward(*terms).contiguous() : torch::Tensor();
  const double* goal_data = task_return_ ? goal_reward.data_ptr<double>() : nullptr;
  const torch::Tensor reward_contiguous = reward->contiguous();
  const float* reward_data = reward_contiguous.data_ptr<float>();
  const float* done_data = done->data_ptr<float>();
  const float* truncated_data = truncated->data_ptr<float>();
  std::vector<int> ended_lengths(r.n, 0);
  for (int i = 0; i < r.n; ++i) {
    returns[i] += reward_data[i];
    ++lengths[i];
    if (goal_data != nullptr) goal_returns[i] += goal_data[i];
    if (done_data[i] > 0.5f) {
      ended_lengths[i] = lengths[i];
      recent_returns_.push_back(returns[i]);
      recent_lengths_.push_back(lengths[i]);
      recent_tracked_.push_back(truncated_data[i] > 0.5f ? 1.0 : 0.0);
      if (task_return_) {
        r.normalized_returns.push_back(task_return_->Normalize(goal_returns[i]));
        r.ends.Add(causes->empty() ? v1::END_CAUSE_UNSPECIFIED : (*causes)[i]);
      }
      returns[i] = 0;
      lengths[i] = 0;
      goal_returns[i] = 0;
    }
  }
  // Only episodes that follow clips tell the server's clip sampler something.
  return TaskFollowsClips(config_.task) ? RecordEpisodeEnds(r.slot, result, done_data, truncated_data, ended_lengths)
                                        : absl::OkStatus();
}

absl::Status Trainer::RecordEpisodeEnds(SessionSlot* slot, const v1::StepResult& result, const float* done,
                                        const float* truncated, const std::vector<int>& ended_lengths) {
  const int n = slot->num_envs();
  std::vector<int32_t> clip, frame;
  std::vector<float> part_error;
  if (absl::Status status = ReadInt32Tensor(result.ended_clip_id(), "StepResult.ended_clip_id", {n}, &clip); !status.ok()) {
    return AsDataLoss(status);
  }
  if (absl::Status status = ReadInt32Tensor(result.ended_frame(), "StepResult.ended_frame", {n}, &frame); !status.ok()) {
    return AsDataLoss(status);
  }
  // Per-part errors are optional on the wire (empty: the failure is reported without them).
  const bool has_parts = result.part_error().shape_size() > 0;
  if (absl::Status status =
          has_parts ? ReadFloatTensor(result.part_error(), "StepResult.part_error", {n, kAnySize}, &part_error)
                    : absl::OkStatus();
      !status.ok()) {
    return AsDataLoss(status);
  }
  const int parts = has_parts ? static_cast<int>(result.part_error().shape(1)) : 0;
  PendingReports& pending = pending_reports_[slot];
  if (pending.generation != slot->generation) pending = PendingReports{slot->generation, {}};
  for (int i = 0; i < n; ++i) {
    if (done[i] <= 0.5f) continue;
    const std::string& name = slot->stream->clip_name(clip[i]);
    if (name.empty()) continue;
    v1::ClipFailure failure;
    failure.set_clip(name);
    failure.set_frame(frame[i]);
    failure.set_terminated(truncated[i] <= 0.5f);
    failure.set_steps(ended_lengths[i]);
    bool finite = true;
    for (int p = 0; p < parts; ++p) finite &= std::isfinite(part_error[i * parts + p]);
    if (failure.terminated() && finite) {
      for (int p = 0; p < parts; ++p) failure.add_part_errors(part_error[i * parts + p]);
    }
    auto& outcome = clip_outcomes_[failure.clip()];
    (failure.terminated() ? outcome.first : outcome.second) += 1;
    pending.failures.push_back(std::move(failure));
  }
  return absl::OkStatus();
}

namespace {

// "a 96%, b 89%, ...": the five clips with the largest shares, largest first, each share as
// `percent` writes it.
std::string FiveLargestShares(std::vector<std::pair<double, std::string>> shares,
                              absl::FunctionRef<std::string(double)> percent) {
  std::sort(shares.rbegin(), shares.rend());
  std::string text;
  for (size_t k = 0; k < std::min<size_t>(5, shares.size()); ++k) {
    absl::StrAppend(&text, k ? ", " : "", shares[k].second, " ", percent(shares[k].first));
  }
  return text;
}

// "a 9.5 %, b 8.7 %, ... (uniform 5.0 %)": where a session's adaptive sampler puts its mass.
std::string MostSampledClips(const v1::SamplerState& state) {
  std::vector<std::pair<double, std::string>> clips;
  for (const v1::ClipSamplingState& clip : state.clips()) clips.emplace_back(clip.probability(), clip.clip());
  if (clips.empty()) return "";
  return absl::StrCat(FiveLargestShares(clips, [](double p) { return absl::StrFormat("%.1f %%", 100 * p); }),
                      absl::StrFormat(" (uniform %.1f %%)", 100.0 / clips.size()));
}

}  // namespace

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
  bool sampler_logged = false;
  for (SessionSlot* slot : servers_->Alive()) {
    PendingReports& pending = pending_reports_[slot];
    if (pending.generation != slot->generation || pending.failures.empty()) continue;
    v1::ReportFailuresRequest request;
    request.set_session_id(slot->stream->opened().session_id());
    request.set_discriminator(discriminator);
    for (v1::ClipFailure& failure : pending.failures) *request.add_failures() = std::move(failure);
    pending.failures.clear();
    auto state = slot->client->ReportFailures(request);
    if (!state.ok()) {
      LogLine("failure report to %s not taken: %s", slot->server, state.status().message());
    } else if (!sampler_logged) {  // the first session that answers; each has its own sampler
      LogLine("sampler of %s: %s", slot->server, MostSampledClips(*state));
      sampler_logged = true;
    }
  }
  // The hardest clips so far: highest failure rate among those seen at least 5 times.
  std::vector<std::pair<double, std::string>> rates;
  for (const auto& [clip, outcome] : clip_outcomes_) {
    const int64_t total = outcome.first + outcome.second;
    if (total >= 5) rates.emplace_back(static_cast<double>(outcome.first) / total, clip);
  }
  const std::string hardest = FiveLargestShares(
      std::move(rates), [](double rate) { return absl::StrCat(static_cast<int>(100 * rate), "%"); });
  if (!hardest.empty()) LogLine("hardest clips (episodes failed): %s", hardest);
}

}  // namespace modskill::learner
