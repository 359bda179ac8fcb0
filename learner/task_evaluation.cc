#include "learner/task_evaluation.h"

#include <functional>
#include <optional>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "learner/policy_import.h"
#include "learner/task_return.h"
#include "learner/wire_torch.h"

namespace modskill::learner {
namespace {

absl::Status Invalid(const std::string& path, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("--checkpoint ", path, ": ", why));
}

// The ModelConfig of an exported task policy, read from its weight shapes.
absl::StatusOr<ModelConfig> TaskConfigOf(const ExportedPolicy& exported, const NetworkLayout& layout) {
  auto head = exported.Mlp("task_head");
  auto controller = exported.Mlp("part0_controller");
  if (!head.ok()) return head.status();
  if (!controller.ok()) return controller.status();
  const int64_t parts = static_cast<int64_t>(layout.parts.size());
  if (head->empty() || controller->empty() || head->back().weight.size(0) % parts != 0) {
    return Invalid(exported.path, absl::StrCat("no task head with one z per part for ", parts, " parts"));
  }
  ModelConfig config = *ModelConfig::Preset("small");
  config.embed_dim = head->back().weight.size(0) / parts;
  config.task_hidden = HiddenSizes(*head);
  config.controller_hidden = HiddenSizes(*controller);
  config.controller_input = ModelConfig::ControllerInput::kProprioception;
  // A skill prior: the tracker's attention was exported beside the head.
  auto value = exported.Mlp("part0_value");
  if (!value.ok()) return value.status();
  config.task_skill_prior = !value->empty();
  if (config.task_skill_prior) {
    config.attention_hidden = HiddenSizes(*value);
    config.attention = exported.Has("part0_key_fc0_weight");
  }
  return config;
}

// Copies the exported task head and controllers into `policy`.
absl::Status CopyTaskPolicy(const ExportedPolicy& exported, ModSkillPolicyImpl& policy) {
  auto head = exported.Mlp("task_head");
  if (!head.ok()) return head.status();
  Mlp task_head = policy.task_head();  // handles that can be written through
  if (absl::Status status = CopyIntoMlp(*head, *task_head, exported.path + ": task_head"); !status.ok()) {
    return status;
  }
  if (policy.config().task_skill_prior != policy.uses_skill_prior()) {
    return Invalid(exported.path, "its skill prior does not fit the session (no reference features to read)");
  }
  if (policy.uses_skill_prior()) {
    SkillAttention attention = policy.attention();  // a handle that can be written through
    if (absl::Status status = CopyAttentionFrom(exported, *attention); !status.ok()) return status;
  }
  for (size_t p = 0; p < policy.controllers().size(); ++p) {
    auto layers = exported.Mlp(absl::StrCat("part", p, "_controller"));
    if (!layers.ok()) return layers.status();
    Mlp controller = policy.controllers()[p]->mlp();
    if (absl::Status status = CopyIntoMlp(*layers, *controller, absl::StrCat(exported.path, ": part ", p, " controller"));
        !status.ok()) {
      return status;
    }
  }
  return absl::OkStatus();
}

// How one run picks z, [n, P, E], from the observation (raw and normalized).
using ZSource = std::function<torch::Tensor(const torch::Tensor& raw_obs, const torch::Tensor& normalized_obs)>;

// One episode in each env (the first each env runs) with z from `z_of`; `z_sum` ([P, E]), when
// given, gathers the z of every step.
absl::StatusOr<TaskEvaluationRow> RunEpisodes(SimulationClient& client, ImportedTaskPolicy& imported,
                                              const TaskEvaluationOptions& options, const std::string& name,
                                              const ZSource& z_of, torch::Tensor* z_sum) {
  v1::SessionConfig config = options.session;
  config.set_num_envs(options.episodes);
  config.set_seed(options.seed);
  auto stream = client.OpenSession(config);
  if (!stream.ok()) return stream.status();
  const v1::EnvSpec& spec = (*stream)->spec();
  const int n = options.episodes;
  const TaskReturn task_return({spec.reward_terms().begin(), spec.reward_terms().end()}, config.max_episode_steps());
  const size_t goal_terms = task_return.goal_names().size();
  std::vector<double> length(n, 0.0), term_sums(n * goal_terms, 0.0);  // [n, G]: each episode's goal terms summed
  std::vector<bool> ended(n, false);
  EpisodeEnds ends;
  int remaining = n;
  const v1::StepResult* result = &(*stream)->opened().initial();
  torch::NoGradGuard no_grad;
  for (int step = 0; remaining > 0; ++step) {
    if (step >= options.max_steps) {
      return absl::DeadlineExceededError(absl::StrCat(name, ": ", remaining, " episodes still running after ", step, " steps"));
    }
    auto obs = WireToTorch(result->obs(), "StepResult.obs", v1::FLOAT32, {n, spec.obs_size()});
    if (!obs.ok()) return obs.status();
    const torch::Tensor normalized = imported.obs_norm->Normalize(*obs);
    const torch::Tensor z = z_of(*obs, normalized);
    if (z_sum != nullptr) *z_sum += z.sum(0);
    const torch::Tensor actions = imported.policy->ControllerActions(normalized, z).contiguous();
    if (absl::Status status = (*stream)->Step(actions.data_ptr<float>()); !status.ok()) return status;
    result = &(*stream)->result();
    auto terms = WireToTorch(result->reward_terms(), "StepResult.reward_terms", v1::FLOAT32, {n, spec.reward_terms_size()});
    auto done = WireToTorch(result->done(), "StepResult.done", v1::UINT8, {n});
    auto causes = ReadEndCauses(*result, n);
    if (!terms.ok()) return terms.status();
    if (!done.ok()) return done.status();
    if (!causes.ok()) return causes.status();
    const torch::Tensor step_terms = task_return.GoalTerms(*terms).contiguous();
    const double* step_values = step_terms.data_ptr<double>();
    for (int i = 0; i < n; ++i) {
      if (ended[i]) continue;
      for (size_t k = 0; k < goal_terms; ++k) term_sums[i * goal_terms + k] += step_values[i * goal_terms + k];
      length[i] += 1;
      if (done->data_ptr<float>()[i] > 0.5f) {
        ended[i] = true, --remaining;
        ends.Add(causes->empty() ? v1::END_CAUSE_UNSPECIFIED : (*causes)[i]);
      }
    }
  }
  (void)(*stream)->Close();
  std::vector<double> returns(n, 0.0), term_shares(goal_terms, 0.0);
  for (int i = 0; i < n; ++i) {
    for (size_t k = 0; k < goal_terms; ++k) {
      const double share = task_return.Normalize(term_sums[i * goal_terms + k]);
      returns[i] += share;
      term_shares[k] += share / n;
    }
  }
  TaskEvaluationRow row{name, MeanOrNan(returns), MeanOrNan(length), n, ends, {}};
  for (size_t k = 0; k < goal_terms; ++k) row.by_term.emplace_back(task_return.goal_names()[k], term_shares[k]);
  return row;
}

}  // namespace

absl::StatusOr<ImportedTaskPolicy> ImportTaskPolicy(const std::string& path, const v1::EnvSpec& task_spec) {
  auto exported = ReadExportedPolicy(path);
  if (!exported.ok()) return exported.status();
  const PolicySpec& spec = exported->spec;
  const NetworkLayout layout = LayoutFromWireSpec(task_spec);
  if (spec.task != layout.task) {
    return Invalid(path, absl::StrCat("a policy for task ", spec.task, ", the session runs ", layout.task,
                                      spec.task == kTrackingTask ? " (evaluate trackers without --task)" : ""));
  }
  if (spec.part_layout != task_spec.part_layout() || spec.obs_size != layout.obs_size ||
      spec.action_size != layout.action_size) {
    return Invalid(path, absl::StrCat("trained on layout ", spec.part_layout, " (obs ", spec.obs_size, ", actions ",
                                      spec.action_size, "); the session has ", task_spec.part_layout(), " (",
                                      layout.obs_size, ", ", layout.action_size, ")"));
  }
  auto config = TaskConfigOf(*exported, layout);
  if (!config.ok()) return config.status();
  ImportedTaskPolicy imported;
  try {
    imported.policy = ModSkillPolicy(layout, *config);
  } catch (const c10::Error& e) {
    return Invalid(path, e.what_without_backtrace());
  }
  if (absl::Status status = CopyTaskPolicy(*exported, *imported.policy); !status.ok()) return status;
  imported.obs_norm = RunningMeanStd(layout.obs_size);
  torch::NoGradGuard no_grad;
  for (const char* name : {"obs_mean", "obs_var"}) {
    if (!exported->Has(name) || exported->tensors.at(name).numel() != layout.obs_size) {
      return Invalid(path, absl::StrCat("no ", name, " of ", layout.obs_size, " features"));
    }
  }
  imported.obs_norm->mean().copy_(exported->tensors.at("obs_mean"));
  imported.obs_norm->var().copy_(exported->tensors.at("obs_var"));
  return imported;
}

absl::StatusOr<TaskEvaluationReport> EvaluateTaskPolicy(SimulationClient& client, ImportedTaskPolicy& imported,
                                                        const std::string& checkpoint_name,
                                                        const TaskEvaluationOptions& options) {
  if (options.episodes < 1) return absl::InvalidArgumentError("--eval_episodes: must be >= 1");
  ModSkillPolicyImpl& policy = *imported.policy;
  const int64_t parts = static_cast<int64_t>(policy.layout().parts.size()), embed = policy.config().embed_dim;
  TaskEvaluationReport report;
  report.task = policy.layout().task;
  report.checkpoint = checkpoint_name;
  report.episode_steps = TaskEpisodeSteps(options.session.max_episode_steps());
  torch::Tensor z_sum = torch::zeros({parts, embed});
  auto trained = RunEpisodes(client, imported, options, "task policy (deterministic)",
                             [&](const torch::Tensor&, const torch::Tensor& obs) { return policy.skills(obs).z; }, &z_sum);
  if (!trained.ok()) return trained.status();
  report.rows.push_back(*trained);
  if (!options.baselines) return report;
  torch::Generator generator = at::detail::createCPUGenerator(options.seed);
  auto random = RunEpisodes(client, imported, options, "random unit z per part, every step",
                            [&](const torch::Tensor&, const torch::Tensor& obs) {
                              return SkillAttentionImpl::NormalizeToSphere(
                                  torch::randn({obs.size(0), parts, embed}, generator));
                            },
                            nullptr);
  if (!random.ok()) return random.status();
  report.rows.push_back(*random);
  const torch::Tensor mean_z = SkillAttentionImpl::NormalizeToSphere(z_sum);  // the direction of the mean z
  auto constant = RunEpisodes(client, imported, options, "constant z (the task policy's mean z per part)",
                              [&](const torch::Tensor&, const torch::Tensor& obs) { return mean_z.expand({obs.size(0), parts, embed}); },
                              nullptr);
  if (!constant.ok()) return constant.status();
  report.rows.push_back(*constant);
  if (!policy.uses_skill_prior()) return report;
  // What the head adds to the prior: the same skills on the prior's z alone.
  const auto prior_z = [&](const torch::Tensor& obs) {
    return policy.TaskZ(obs, torch::zeros({obs.size(0), parts * embed}));
  };
  auto prior = RunEpisodes(client, imported, options, "the skill prior alone (zero displacement)",
                           [&](const torch::Tensor&, const torch::Tensor& obs) { return prior_z(obs); }, nullptr);
  if (!prior.ok()) return prior.status();
  report.rows.push_back(*prior);
  if (options.teacher == nullptr) return report;
  const NetworkLayout& layout = policy.layout();
  const torch::Tensor supervised = options.teacher_parts.view({1, parts, 1});
  auto teacher = RunEpisodes(client, imported, options, "the teacher (nearest held pose's z; prior elsewhere)",
                             [&](const torch::Tensor& raw, const torch::Tensor& obs) {
                               const torch::Tensor goals = raw.slice(1, layout.goal_start, layout.goal_start + layout.goal_size);
                               return supervised * options.teacher->NearestZ(goals) + (1 - supervised) * prior_z(obs);
                             },
                             nullptr);
  if (!teacher.ok()) return teacher.status();
  report.rows.push_back(*teacher);
  return report;
}

std::string TaskEvaluationReport::ToJson() const {
  nlohmann::json json;
  json["task"] = task;
  json["checkpoint"] = checkpoint;
  json["normalized_by_steps"] = episode_steps;
  for (const TaskEvaluationRow& row : rows) {
    nlohmann::json ended_by = nlohmann::json::object();
    const std::vector<std::string> names = EpisodeEnds::Names();
    const std::vector<int> counts = row.ends.Counts();
    for (size_t c = 0; c < names.size(); ++c) ended_by[names[c]] = counts[c];
    nlohmann::json by_term = nlohmann::json::object();
    for (const auto& [term, share] : row.by_term) by_term[term] = share;
    json["runs"].push_back({{"z_source", row.z_source},
                            {"mean_normalized_return", row.mean_normalized_return},
                            {"mean_episode_length", row.mean_episode_length},
                            {"episodes", row.episodes},
                            {"ended_by", ended_by},
                            {"by_term", by_term}});
  }
  return json.dump(1);
}

std::string TaskEvaluationReport::ToMarkdown() const {
  std::string md = absl::StrFormat(
      "Task %s, %s: the same frozen skills driven by different z. Normalized return: per episode, the sum of the "
      "reward terms other than energy divided by %d steps.\n\n"
      "| z for the skills | normalized return | by term | episode length (steps) | episodes | ended by |\n"
      "|---|---|---|---|---|---|\n",
      task, checkpoint, episode_steps);
  for (const TaskEvaluationRow& row : rows) {
    std::vector<std::string> shares;
    for (const auto& [term, share] : row.by_term) shares.push_back(absl::StrFormat("%s %.3f", term, share));
    absl::StrAppendFormat(&md, "| %s | %.3f | %s | %.1f | %d | %s |\n", row.z_source, row.mean_normalized_return,
                          absl::StrJoin(shares, ", "), row.mean_episode_length, row.episodes, row.ends.Summary());
  }
  return md;
}

}  // namespace modskill::learner
