// FamilyTrainer's collection: horizon steps of every env, and each ended episode's bookkeeping
// (visits for the curriculum, an offer to the elite set).
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "learner/family/family_trainer.h"
#include "learner/wire_torch.h"

namespace modskill::learner::family {

absl::StatusOr<FamilyTrainer::StepTensors> FamilyTrainer::ReadResult() const {
  const v1::StepResult& r = stream_->result();
  const int64_t n = config_.num_envs, obs_size = obs_size_, dims = space_->dims();
  StepTensors t;
  struct Field {
    const v1::Tensor& wire;
    const char* name;
    v1::DType dtype;
    std::vector<int64_t> shape;
    torch::Tensor* out;
  };
  const Field fields[] = {{r.obs(), "obs", v1::FLOAT32, {n, obs_size}, &t.obs},
                          {r.reward(), "reward", v1::FLOAT32, {n}, &t.reward},
                          {r.spike_reward(), "spike_reward", v1::FLOAT32, {n}, &t.spike},
                          {r.phase_step(), "phase_step", v1::FLOAT32, {n}, &t.phase_step},
                          {r.done(), "done", v1::UINT8, {n}, &t.done},
                          {r.truncated(), "truncated", v1::UINT8, {n}, &t.truncated},
                          {r.fitness(), "fitness", v1::FLOAT32, {n}, &t.fitness},
                          {r.ended_family_params(), "ended_family_params", v1::FLOAT32, {n, dims}, &t.ended_params}};
  for (const Field& field : fields) {
    auto tensor = WireToTorch(field.wire, absl::StrCat("StepResult.", field.name), field.dtype, field.shape);
    if (!tensor.ok()) return tensor.status();
    *field.out = *std::move(tensor);
  }
  return t;
}

void FamilyTrainer::RecordStep(int env, const float* action, float phase_step) {
  EnvEpisode& episode = episodes_[env];
  episode.phases.push_back(static_cast<float>(episode.phase));
  for (int a = 0; a < action_size_; ++a) {
    // What the server applied: a clamped displacement, and the time warp as the log of its step.
    episode.actions.push_back(a == time_warp_ ? std::log(std::max(phase_step, 1e-6f)) : std::clamp(action[a], -1.f, 1.f));
  }
  episode.phase += phase_step;
  ++episode.steps;
}

absl::Status FamilyTrainer::Collect(Rollout* rollout, FamilyIterationStats* stats) {
  const int64_t n = config_.num_envs;
  torch::NoGradGuard no_grad;
  for (int t = 0; t < config_.horizon; ++t) {
    const torch::Tensor mean = model_->Mean(obs_);
    const torch::Tensor actions = mean + torch::exp(model_->log_std()) * torch::randn_like(mean);
    rollout->obs.push_back(obs_);
    rollout->actions.push_back(actions);
    rollout->log_probs.push_back(model_->LogProb(mean, actions));
    rollout->values.push_back(model_->Value(obs_));
    const torch::Tensor sent = actions.contiguous();
    if (absl::Status status = stream_->Step(sent.data_ptr<float>()); !status.ok()) return status;
    auto step = ReadResult();
    if (!step.ok()) return step.status();
    rollout->rewards.push_back(step->reward);
    rollout->spikes.push_back(step->spike);
    rollout->phase_steps.push_back(step->phase_step.clamp_min(1e-6));
    rollout->dones.push_back(step->done);
    for (int i = 0; i < n; ++i) {
      RecordStep(i, sent[i].data_ptr<float>(), step->phase_step[i].item<float>());
      episodes_[i].total_reward += step->reward[i].item<float>();
      if (step->done[i].item<float>() == 0) continue;
      const bool terminated = step->truncated[i].item<float>() == 0;
      if (absl::Status status = EndEpisode(i, terminated, step->fitness[i].item<float>(),
                                           step->ended_params[i], stats);
          !status.ok()) {
        return status;
      }
      template_obs_ = step->obs[i].clone();
    }
    obs_ = step->obs;
    env_steps_ += n;
  }
  rollout->last_values = model_->Value(obs_);
  return absl::OkStatus();
}

namespace {

// The episode's actions at each of the clip's frames: the step whose phase interval holds it.
torch::Tensor ResampleToFrames(const std::vector<float>& phases, const std::vector<float>& actions, int64_t frames,
                               int64_t action_size) {
  torch::Tensor trajectory = torch::zeros({frames, action_size});
  size_t step = 0;
  for (int64_t f = 0; f < frames; ++f) {
    while (step + 1 < phases.size() && phases[step + 1] <= f) ++step;
    for (int64_t a = 0; a < action_size; ++a) trajectory[f][a] = actions[step * action_size + a];
  }
  return trajectory;
}

}  // namespace

absl::Status FamilyTrainer::EndEpisode(int env, bool terminated, float fitness, const torch::Tensor& ended_params,
                                       FamilyIterationStats* stats) {
  EnvEpisode& episode = episodes_[env];
  std::vector<double> a(ended_params.size(0));
  for (size_t d = 0; d < a.size(); ++d) a[d] = ended_params[d].item<float>();
  // A row from before the first assignment can sit a float's rounding outside its range.
  for (size_t d = 0; d < a.size(); ++d) a[d] = std::clamp(a[d], config_.ranges[d].lo, config_.ranges[d].hi);
  auto u = space_->Normalize(a);
  if (!u.ok()) return u.status();
  if (absl::Status status = curriculum_->AddVisited(*u); !status.ok()) return status;
  ++stats->episodes;
  stats->mean_return += episode.total_reward;
  stats->mean_length += episode.steps;
  stats->mean_fitness += fitness;
  ++batch_episodes_;
  // Only a motion played to the clip's end is a candidate: a fall is no member of the family.
  if (!terminated && episode.steps > 0) {
    auto entered = elites_->Offer(*u, fitness, ResampleToFrames(episode.phases, episode.actions, frames_, action_size_));
    if (!entered.ok()) return entered.status();
    batch_new_elites_ += *entered;
  }
  const int slot = episode.batch_slot;
  episode = EnvEpisode();
  episode.batch_slot = slot;
  return absl::OkStatus();
}

}  // namespace modskill::learner::family
