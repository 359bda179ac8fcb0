#include "learner/trainer_config.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "common/policy/reference_frames.h"
#include "common/task_settings.h"
#include "learner/server_discovery.h"

namespace modskill::learner {
namespace {

// Hidden layer widths from a flag: each in [1, 65536].
absl::Status ValidateWidths(absl::string_view flag, const std::vector<int64_t>& sizes) {
  for (int64_t size : sizes) {
    if (size < 1 || size > 65536) return absl::InvalidArgumentError(absl::StrCat(flag, ": ", size, " must be in [1, 65536]"));
  }
  return absl::OkStatus();
}

// The settings the server will use: the flags', the server's defaults where a flag is 0 (unset),
// checked against the server's own bounds (TaskSettings::Validate) under the flags' names.
absl::Status ValidateTaskSettings(const TrainerConfig& c) {
  if (!c.task_reach_center.empty() && c.task_reach_center.size() != 3) {
    return absl::InvalidArgumentError(absl::StrCat("--task_reach_center: ", c.task_reach_center.size(),
                                                   " values; it takes forward,left,height in m"));
  }
  TaskSettings settings;
  for (const auto& [flag, field] : {std::pair<double, double*>{c.task_min_speed, &settings.min_speed},
                                    {c.task_max_speed, &settings.max_speed},
                                    {c.task_min_goal_interval_s, &settings.min_goal_interval_s},
                                    {c.task_max_goal_interval_s, &settings.max_goal_interval_s},
                                    {c.task_reach_box_size, &settings.reach_box_size},
                                    {c.task_steering_rate, &settings.steering_rate}}) {
    if (flag != 0) *field = flag;  // NaN too: Validate names it
  }
  for (size_t axis = 0; axis < c.task_reach_center.size(); ++axis) settings.reach_center[axis] = c.task_reach_center[axis];
  return settings.Validate([](absl::string_view field) {
    return absl::StartsWith(field, "reach_center") ? std::string("--task_reach_center") : absl::StrCat("--task_", field);
  });
}

// --task, --skills and the task's settings and sizes; the task's name is checked against the
// server's list when the trainer starts.
absl::Status ValidateTask(const TrainerConfig& c) {
  if (c.task.empty()) return absl::InvalidArgumentError("--task: empty (tracking, or a task the server lists)");
  if (IsTrackingTask(c.task) != c.skills.empty()) {
    return absl::InvalidArgumentError(
        IsTrackingTask(c.task) ? std::string("--skills: only with a --task other than tracking")
                               : absl::StrCat("--skills: required with --task ", c.task,
                                              " (a tracker's policy.pt trained with --controller_input proprioception)"));
  }
  if (!c.train_parts.empty() && c.init_from.empty()) {
    return absl::InvalidArgumentError("--train_parts: needs --init_from (the tracker whose other parts stay frozen)");
  }
  if (c.frozen_parts_act_on_mean && c.train_parts.empty()) {
    return absl::InvalidArgumentError("--frozen_parts_act_on_mean: only with --train_parts (no part is frozen otherwise)");
  }
  if (!c.train_attention && c.train_parts.empty()) {
    return absl::InvalidArgumentError("--train_attention=false: only with --train_parts");
  }
  if (c.fresh_parts && c.train_parts.empty()) {
    return absl::InvalidArgumentError("--fresh_parts: only with --train_parts (the parts that start fresh)");
  }
  if (!c.init_from.empty() && !IsTrackingTask(c.task)) {
    return absl::InvalidArgumentError(absl::StrCat("--init_from: tracking only, not with --task ", c.task, " (use --skills)"));
  }
  const std::pair<const char*, bool> tracking_only[] = {
      {"--reward_parts", !c.reward_parts.empty()},
      {"--reward_relative_to_root", c.reward_relative_to_root},
      {"--loop_clips", c.loop_clips},
      {"--anchor_reference", c.anchor_reference},
      {"--reference_frames", c.reference_frames > 1}};
  if (c.anchor_position_only && !c.anchor_reference) {
    return absl::InvalidArgumentError("--anchor_position_only: only with --anchor_reference");
  }
  if (absl::Status status = ValidateReferenceFrames(c.reference_frames, "--reference_frames"); !status.ok()) {
    return status;
  }
  if (c.reference_frames > 1 && (c.loop_clips || c.anchor_reference)) {
    return absl::InvalidArgumentError(absl::StrCat("--reference_frames: ", c.reference_frames, " with ",
                                                   c.loop_clips ? "--loop_clips" : "--anchor_reference",
                                                   "; only a clip tracked where it is"));
  }
  for (const auto& [flag, given] : tracking_only) {
    if (given && !IsTrackingTask(c.task)) {
      return absl::InvalidArgumentError(absl::StrCat(flag, ": tracking only, not with --task ", c.task));
    }
  }
  if (!IsTrackingTask(c.task) && c.model.whole_body) {
    return absl::InvalidArgumentError("--whole_body: not with a --task (the skills are per-part controllers)");
  }
  if (!(std::isfinite(c.model.task_log_std) && c.model.task_log_std > -20 && c.model.task_log_std < 2)) {
    return absl::InvalidArgumentError(absl::StrCat("--task_log_std: ", c.model.task_log_std, " must be in (-20, 2)"));
  }
  if (absl::Status status = ValidateWidths("--task_hidden", c.model.task_hidden); !status.ok()) return status;
  if (!c.task_parts.empty() && IsTrackingTask(c.task)) {
    return absl::InvalidArgumentError("--task_parts: only with a --task (the parts whose z the task head displaces)");
  }
  if (!c.task_parts.empty() && !c.model.task_skill_prior) {
    return absl::InvalidArgumentError(
        "--task_parts: needs --task_skill_prior (the parts left out play the prior's z; without it they have none)");
  }
  if (!c.task_teacher.empty() && c.task != "reach") {
    return absl::InvalidArgumentError(absl::StrCat("--task_teacher: reach only, not with --task ", c.task));
  }
  if (!(std::isfinite(c.task_teacher_weight) && c.task_teacher_weight >= 0 && c.task_teacher_weight <= 100)) {
    return absl::InvalidArgumentError(absl::StrCat("--task_teacher_weight: ", c.task_teacher_weight, " must be in [0, 100]"));
  }
  if (c.task_teacher_steps < 0) {
    return absl::InvalidArgumentError(absl::StrCat("--task_teacher_steps: ", c.task_teacher_steps, " must be >= 0"));
  }
  return ValidateTaskSettings(c);
}

}  // namespace

absl::StatusOr<ImitationKernels> ParseImitationKernels(absl::string_view text) {
  ImitationKernels kernels;
  if (text.empty()) return kernels;
  const auto bad = [&](absl::string_view part, absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat("--imitation_kernels: '", part.substr(0, 64), "' ", why));
  };
  std::vector<std::string> seen;
  for (absl::string_view part : absl::StrSplit(text, ',')) {
    const std::vector<absl::string_view> name_value = absl::StrSplit(part, absl::MaxSplits('=', 1));
    double value = 0;
    if (name_value.size() != 2 || !absl::SimpleAtod(name_value[1], &value)) return bad(part, "is not TERM=K");
    double* target = name_value[0] == "pos"       ? &kernels.pos
                     : name_value[0] == "rot"     ? &kernels.rot
                     : name_value[0] == "vel"     ? &kernels.vel
                     : name_value[0] == "ang_vel" ? &kernels.ang_vel
                                                  : nullptr;
    if (target == nullptr) return bad(part, "names no term (pos, rot, vel, ang_vel)");
    if (std::find(seen.begin(), seen.end(), name_value[0]) != seen.end()) return bad(part, "repeats its term");
    seen.emplace_back(name_value[0]);
    if (!(std::isfinite(value) && value >= 0 && value <= 10000)) return bad(part, "must be in [0, 10000] (0: the default)");
    *target = value;
  }
  return kernels;
}

std::string ImitationKernelsText(const ImitationKernels& kernels) {
  std::vector<std::string> parts;
  const std::pair<const char*, double> terms[] = {
      {"pos", kernels.pos}, {"rot", kernels.rot}, {"vel", kernels.vel}, {"ang_vel", kernels.ang_vel}};
  for (const auto& [name, value] : terms) {
    if (value != 0) parts.push_back(absl::StrCat(name, "=", value));
  }
  return absl::StrJoin(parts, ",");
}

absl::StatusOr<TrainerConfig> TrainerConfig::ForPreset(const std::string& preset) {
  auto model = ModelConfig::Preset(preset);
  if (!model.ok()) return model.status();
  TrainerConfig config;
  config.model = *model;
  if (preset == "small") {
    // Less style reward tracks closer: on the walk, the median of 30 exports per run 26.0 against
    // 30.5 mm at 1.64 M steps (README, Performance, "Learning").
    config.amp_reward_weight = 0.2;
    config.task_reward_weight = 0.8;
  }
  if (preset == "paper") {
    // docs/DESIGN.md section 3 (PHC): lr 2e-5, horizon 32, minibatch 16384, 6 epochs, 3072 envs.
    config.learning_rate = 2e-5;
    config.discriminator_learning_rate = 2e-5;
    config.epochs = 6;
    config.discriminator_epochs = 2;
    config.minibatch_size = 16384;
    config.envs_per_server = 3072;
    // The paper's mapping and termination: absolute PD targets, 0.25 m on every body.
    config.action_mode = "absolute";
    config.termination_bodies = "all";
  }
  return config;
}

absl::Status TrainerConfig::Validate() const {
  auto bad = [](absl::string_view field, auto value, absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat("--", field, ": ", value, " ", why));
  };
  if (servers.empty()) return absl::InvalidArgumentError("--servers: no server given");
  if (absl::Status status = ValidateServerSpecs(servers); !status.ok()) return status;
  if (envs_per_server < 1) return bad("envs_per_server", envs_per_server, "must be >= 1");
  if (sessions_per_server < 1 || sessions_per_server > envs_per_server) {
    return bad("sessions_per_server", sessions_per_server, "must be in [1, envs_per_server]");
  }
  if (iterations < 0) return bad("iterations", iterations, "must be >= 0");
  if (horizon < 1) return bad("horizon", horizon, "must be >= 1");
  if (model.whole_body && model.controller_input == ModelConfig::ControllerInput::kProprioception) {
    return absl::InvalidArgumentError("--controller_input proprioception: not with --whole_body (per-part controllers only)");
  }
  if (epochs < 1) return bad("epochs", epochs, "must be >= 1");
  if (minibatch_size < 1) return bad("minibatch_size", minibatch_size, "must be >= 1");
  if (!(learning_rate > 0 && learning_rate < 1)) return bad("learning_rate", learning_rate, "must be in (0, 1)");
  if (learning_rate_decay_steps < 0) return bad("learning_rate_decay_steps", learning_rate_decay_steps, "must be >= 0");
  if (!(learning_rate_floor > 0 && learning_rate_floor <= 1)) {
    return bad("learning_rate_floor", learning_rate_floor, "must be in (0, 1]");
  }
  if (!(critic_learning_rate >= 0 && critic_learning_rate < 1)) {
    return bad("critic_learning_rate", critic_learning_rate, "must be in [0, 1) (0: --learning_rate)");
  }
  if (!(gamma > 0 && gamma <= 1)) return bad("gamma", gamma, "must be in (0, 1]");
  if (!(lambda >= 0 && lambda <= 1)) return bad("lambda", lambda, "must be in [0, 1]");
  if (amp_samples < 1) return bad("amp_samples", amp_samples, "must be >= 1");
  if (model.amp_frames < 0) return bad("amp_frames", model.amp_frames, "must be >= 0 (0: the server's whole AMP history)");
  if (task_reward_weight < 0 || amp_reward_weight < 0) return absl::InvalidArgumentError("reward weights must be >= 0");
  if (!(energy_weight >= 0 && energy_weight <= 100)) return bad("energy_weight", energy_weight, "must be in [0, 100]");
  for (double k : {imitation_kernels.pos, imitation_kernels.rot, imitation_kernels.vel, imitation_kernels.ang_vel}) {
    if (!(k >= 0 && k <= 10000)) return bad("imitation_kernels", k, "must be in [0, 10000] (0: the default)");
  }
  if (noise_hold_steps < 1 || noise_hold_steps > 10000) {
    return bad("noise_hold_steps", noise_hold_steps, "must be in [1, 10000]");
  }
  if (imitation_kernels.any() && !TaskFollowsClips(task)) {
    return absl::InvalidArgumentError(absl::StrCat("--imitation_kernels: task ", task, " has no imitation reward"));
  }
  if (run_dir.empty()) return absl::InvalidArgumentError("--run_dir: required");
  if (report_every < 0) return bad("report_every", report_every, "must be >= 0");
  if (checkpoint_every < 1) return bad("checkpoint_every", checkpoint_every, "must be >= 1");
  if (update_threads < 0 || update_threads > 256) return bad("update_threads", update_threads, "must be in [0, 256]");
  if (!(server_timeout_s > 0)) return bad("server_timeout_s", server_timeout_s, "must be > 0");
  auto mode = ParseActionMode(action_mode);
  if (!mode.ok()) return absl::InvalidArgumentError(absl::StrCat("--action_mode: ", mode.status().message()));
  if (absl::Status status = ActionMapping{*mode, residual_scale}.Validate("--residual_scale"); !status.ok()) {
    return status;
  }
  if (absl::Status status = ValidateTerminationDistance(termination_distance); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("--", status.message()));
  }
  if (auto bodies = ParseTerminationBodies(termination_bodies); !bodies.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("--termination_bodies: ", bodies.status().message()));
  }
  if (absl::Status status = ValidateTask(*this); !status.ok()) return status;
  for (const auto& [flag, sizes] : {std::pair{"--controller_hidden", &model.controller_hidden},
                                    std::pair{"--critic_hidden", &model.critic_hidden}}) {
    if (absl::Status status = ValidateWidths(flag, *sizes); !status.ok()) return status;
  }
  if (absl::Status status = ValidateDataParallelOptions(data_parallel); !status.ok()) return status;
  if (curriculum_start != 0 || curriculum_end != 0) {
    if (!ValidateTerminationDistance(curriculum_start).ok() || !ValidateTerminationDistance(curriculum_end).ok()) {
      return absl::InvalidArgumentError(absl::StrCat("--termination_curriculum: ", curriculum_start, ":",
                                                     curriculum_end, " distances must be in (0, ",
                                                     kMaxTerminationDistance, "] m"));
    }
    if (curriculum_start < curriculum_end) {
      return absl::InvalidArgumentError(absl::StrCat("--termination_curriculum: start ", curriculum_start,
                                                     " is below end ", curriculum_end, " (it starts loose and tightens)"));
    }
  }
  return absl::OkStatus();
}

bool IsTrackingTask(const std::string& task) { return task == "tracking"; }

void WriteTaskSettings(const TrainerConfig& config, v1::TaskSettings* settings) {
  settings->set_min_speed(static_cast<float>(config.task_min_speed));
  settings->set_max_speed(static_cast<float>(config.task_max_speed));
  settings->set_min_goal_interval_s(static_cast<float>(config.task_min_goal_interval_s));
  settings->set_max_goal_interval_s(static_cast<float>(config.task_max_goal_interval_s));
  if (config.task_reach_box_size > 0) settings->set_reach_box_size(static_cast<float>(config.task_reach_box_size));
  if (config.task_steering_rate > 0) settings->set_steering_rate(static_cast<float>(config.task_steering_rate));
  if (config.task_reach_center.size() == 3) {
    settings->set_reach_center_x(static_cast<float>(config.task_reach_center[0]));
    settings->set_reach_center_y(static_cast<float>(config.task_reach_center[1]));
    settings->set_reach_center_z(static_cast<float>(config.task_reach_center[2]));
  }
}

absl::Status CheckTaskOffered(const v1::EnvSpec& described, const std::string& task, const std::string& server) {
  std::vector<std::string> offered;
  for (const v1::TaskInfo& info : described.tasks()) {
    if (info.name() == task) return absl::OkStatus();
    offered.push_back(info.name());
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "--task ", task, ": not a task of ", server, " (it offers ",
      offered.empty() ? "tracking only: a server without task envs" : absl::StrJoin(offered, ", "), ")"));
}

bool TaskFollowsClips(const std::string& task) { return task == "tracking" || task == "vr_tracking"; }

ActionMode ActionModeOf(const TrainerConfig& config) {
  return config.action_mode == "residual" ? ActionMode::kResidual : ActionMode::kAbsolute;
}

TerminationBodies TerminationBodiesOf(const TrainerConfig& config) {
  return ParseTerminationBodies(config.termination_bodies).value_or(TerminationBodies::kAll);
}

namespace {

// A task run's part of config.json: its skills, head and goal settings.
void AddTaskSettings(const TrainerConfig& config, nlohmann::json& json) {
  json["skills"] = config.skills;
  json["task_hidden"] = config.model.task_hidden;
  json["task_log_std"] = config.model.task_log_std;
  json["task_skill_prior"] = config.model.task_skill_prior;
  if (!config.task_parts.empty()) json["task_parts"] = config.task_parts;
  if (!config.task_teacher.empty()) {
    json["task_teacher"] = config.task_teacher;
    json["task_teacher_weight"] = config.task_teacher_weight;
    json["task_teacher_steps"] = config.task_teacher_steps;
  }
  json["task_settings"] = {{"min_speed", config.task_min_speed},
                           {"max_speed", config.task_max_speed},
                           {"min_goal_interval_s", config.task_min_goal_interval_s},
                           {"max_goal_interval_s", config.task_max_goal_interval_s}};
  if (config.task_reach_box_size > 0) json["task_settings"]["reach_box_size"] = config.task_reach_box_size;
  if (!config.task_reach_center.empty()) json["task_settings"]["reach_center"] = config.task_reach_center;
  if (config.task_steering_rate > 0) json["task_settings"]["steering_rate"] = config.task_steering_rate;
}

}  // namespace

std::string TrainerConfig::ToJson() const {
  nlohmann::json json;
  json["servers"] = servers;
  json["envs_per_server"] = envs_per_server;
  json["sessions_per_server"] = sessions_per_server;
  json["part_layout"] = part_layout;
  json["motions"] = motions;
  json["preset"] = model.preset;
  json["whole_body"] = model.whole_body;
  json["attention"] = model.attention;
  json["controller_input"] = ControllerInputName(model.controller_input);
  json["embed_dim"] = model.embed_dim;
  json["controller_hidden"] = model.controller_hidden;
  json["critic_hidden"] = model.critic_hidden;
  json["amp_frames"] = model.amp_frames;
  json["iterations"] = iterations;
  json["horizon"] = horizon;
  json["epochs"] = epochs;
  json["minibatch_size"] = minibatch_size;
  json["normalize_value"] = normalize_value;
  json["learning_rate"] = learning_rate;
  json["learning_rate_decay_steps"] = learning_rate_decay_steps;
  json["learning_rate_floor"] = learning_rate_floor;
  json["critic_learning_rate"] = critic_learning_rate;
  json["gamma"] = gamma;
  json["lambda"] = lambda;
  json["clip_ratio"] = clip_ratio;
  json["task_reward_weight"] = task_reward_weight;
  json["amp_reward_weight"] = amp_reward_weight;
  json["energy_weight"] = energy_weight;
  json["imitation_kernels"] = ImitationKernelsText(imitation_kernels);
  json["noise_hold_steps"] = noise_hold_steps;
  json["discriminator_learning_rate"] = discriminator_learning_rate;
  json["gradient_penalty_weight"] = gradient_penalty_weight;
  json["seed"] = seed;
  json["report_every"] = report_every;
  json["action_mode"] = action_mode;
  json["residual_scale"] = residual_scale;
  json["termination_distance"] = termination_distance;
  json["termination_bodies"] = termination_bodies;
  json["update_threads"] = update_threads;
  json["collect_during_update"] = collect_during_update;
  json["termination_curriculum"] = {curriculum_start, curriculum_end};
  json["task"] = task;
  json["loop_clips"] = loop_clips;
  json["anchor_reference"] = anchor_reference;
  if (anchor_position_only) json["anchor_position_only"] = true;
  if (reference_frames != 1) json["reference_frames"] = reference_frames;
  if (!init_from.empty()) {
    json["init_from"] = init_from;
    json["train_parts"] = train_parts;
    json["train_attention"] = train_attention;
    json["fresh_parts"] = fresh_parts;
    json["frozen_parts_act_on_mean"] = frozen_parts_act_on_mean;
  }
  if (!reward_parts.empty()) json["reward_parts"] = reward_parts;
  if (reward_relative_to_root) json["reward_relative_to_root"] = true;
  if (!IsTrackingTask(task)) AddTaskSettings(*this, json);
  if (data_parallel.world_size > 1) {
    json["world_size"] = data_parallel.world_size;
    json["rendezvous"] = data_parallel.rendezvous;
  }
  return json.dump(1);
}

}  // namespace modskill::learner
