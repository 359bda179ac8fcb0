#include "learner/trainer_config.h"

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"

namespace modskill::learner {

absl::StatusOr<TrainerConfig> TrainerConfig::ForPreset(const std::string& preset) {
  auto model = ModelConfig::Preset(preset);
  if (!model.ok()) return model.status();
  TrainerConfig config;
  config.model = *model;
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
  if (!(gamma > 0 && gamma <= 1)) return bad("gamma", gamma, "must be in (0, 1]");
  if (!(lambda >= 0 && lambda <= 1)) return bad("lambda", lambda, "must be in [0, 1]");
  if (amp_samples < 1) return bad("amp_samples", amp_samples, "must be >= 1");
  if (task_reward_weight < 0 || amp_reward_weight < 0) return absl::InvalidArgumentError("reward weights must be >= 0");
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

ActionMode ActionModeOf(const TrainerConfig& config) {
  return config.action_mode == "residual" ? ActionMode::kResidual : ActionMode::kAbsolute;
}

TerminationBodies TerminationBodiesOf(const TrainerConfig& config) {
  return ParseTerminationBodies(config.termination_bodies).value_or(TerminationBodies::kAll);
}

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
  json["iterations"] = iterations;
  json["horizon"] = horizon;
  json["epochs"] = epochs;
  json["minibatch_size"] = minibatch_size;
  json["learning_rate"] = learning_rate;
  json["gamma"] = gamma;
  json["lambda"] = lambda;
  json["clip_ratio"] = clip_ratio;
  json["task_reward_weight"] = task_reward_weight;
  json["amp_reward_weight"] = amp_reward_weight;
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
  return json.dump(1);
}

}  // namespace modskill::learner
