// FamilyTrainer::Evaluate: the policy's mean actions at chosen parameters, and what the motion
// did physically (the root's apex, the highest an end effector got, e.g. a kicking foot, the
// time with every foot off the floor), read from the
// observation's self features (root height; each body's position relative to the root, whose z
// the heading frame keeps).
#include <algorithm>
#include <string>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "learner/family/family_trainer.h"

namespace modskill::learner::family {
namespace {

// Where the root's height and each foot's height above the root sit in the observation.
struct HeightIndices {
  int root = -1;
  std::vector<int> feet;
  std::vector<int> effectors;  // ankles, toes, wrists, hands
};

HeightIndices FindHeights(const v1::EnvSpec& spec) {
  HeightIndices indices;
  for (const v1::BodyPart& part : spec.parts()) {
    for (int k = 0; k < part.bodies_size() && k < part.self_obs_size(); ++k) {
      const std::string& body = part.bodies(k);
      if (body == spec.body_names(0)) indices.root = part.self_obs(k).start();
      const int local_z = part.self_obs(k).start() + 2;
      const bool foot = absl::StrContains(body, "Ankle") || absl::StrContains(body, "Toe");
      if (foot) indices.feet.push_back(local_z);
      if (foot || absl::StrContains(body, "Wrist") || absl::StrContains(body, "Hand")) indices.effectors.push_back(local_z);
    }
  }
  return indices;
}

// One env's evaluated episode: waiting for the episode it was in to end, recording, done.
struct Watch {
  int stage = 0;
  double apex = 0, highest_effector = 0;
  int flight_steps = 0, steps = 0;
  std::vector<float> foot_ground;  // per foot: its height at the episode's first frame + 3 cm
  FamilyRolloutResult result;
};

void Observe(const HeightIndices& h, const float* obs, Watch* watch) {
  const float root = obs[h.root];
  if (watch->foot_ground.empty()) {
    for (int foot : h.feet) watch->foot_ground.push_back(root + obs[foot] + 0.03f);
  }
  watch->apex = std::max(watch->apex, static_cast<double>(root));
  for (int e : h.effectors) watch->highest_effector = std::max(watch->highest_effector, static_cast<double>(root + obs[e]));
  bool airborne = true;
  for (size_t f = 0; f < h.feet.size(); ++f) airborne &= root + obs[h.feet[f]] > watch->foot_ground[f];
  watch->flight_steps += airborne;
}

}  // namespace

absl::StatusOr<std::vector<FamilyRolloutResult>> FamilyTrainer::Evaluate(const std::vector<std::vector<double>>& params,
                                                                         int max_steps) {
  if (params.empty() || static_cast<int>(params.size()) > config_.num_envs) {
    return absl::InvalidArgumentError(absl::StrCat("family eval: 1 to ", config_.num_envs, " parameter vectors"));
  }
  const HeightIndices heights = FindHeights(stream_->spec());
  if (heights.root < 0 || heights.feet.empty()) return absl::InternalError("family eval: no root or feet in the spec");
  std::vector<float> rows;
  std::vector<Watch> watches(config_.num_envs);
  for (int i = 0; i < config_.num_envs; ++i) {
    const std::vector<double>& a = params[i % params.size()];
    if (absl::StatusOr<std::vector<double>> u = space_->Normalize(a); !u.ok()) return u.status();
    for (double value : a) rows.push_back(static_cast<float>(value));
    watches[i].result.params = a;
  }
  stream_->SetFamilyParameters(rows);
  torch::NoGradGuard no_grad;
  const double dt = stream_->spec().control_dt();
  for (int step = 0; step < max_steps; ++step) {
    const torch::Tensor actions = model_->Mean(obs_).contiguous();
    if (absl::Status status = stream_->Step(actions.data_ptr<float>()); !status.ok()) return status;
    auto result = ReadResult();
    if (!result.ok()) return result.status();
    obs_ = result->obs;
    bool all_done = true;
    for (int i = 0; i < config_.num_envs; ++i) {
      Watch& w = watches[i];
      const bool ended = result->done[i].item<float>() != 0;
      if (w.stage == 1 && ended) {
        w.result = {w.result.params, w.apex, w.highest_effector, w.flight_steps * dt, result->fitness[i].item<float>(),
                    w.steps + 1, result->truncated[i].item<float>() != 0};
        w.stage = 2;
      } else if (w.stage == 1) {
        ++w.steps;
        Observe(heights, obs_[i].data_ptr<float>(), &w);
      }
      if (w.stage == 0 && ended) {
        w.stage = 1;  // the row now holds the first observation of an episode at its parameters
        Observe(heights, obs_[i].data_ptr<float>(), &w);
      }
      all_done &= w.stage == 2;
    }
    if (all_done) break;
  }
  AssignBatch();  // training goes on with the curriculum's vectors
  std::vector<FamilyRolloutResult> results;
  for (size_t k = 0; k < params.size(); ++k) {
    if (watches[k].stage != 2) {
      return absl::DeadlineExceededError(absl::StrCat("family eval: no episode ended within ", max_steps, " steps"));
    }
    results.push_back(watches[k].result);
  }
  return results;
}

}  // namespace modskill::learner::family
