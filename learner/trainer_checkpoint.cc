// The trainer's checkpoint (every network, optimizer and normalizer, the curriculum, counters)
// and the shipped policy export.
#include <sstream>
#include <string>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "common/wire/physics_wire.h"
#include "common/wire/policy_spec_wire.h"
#include "learner/policy_export.h"
#include "learner/trainer.h"

namespace modskill::learner {

absl::Status Trainer::SaveCheckpoint(const std::string& path) {
  absl::StatusOr<std::string> state = SerializeState();
  if (!state.ok()) return absl::Status(state.status().code(), absl::StrCat(path, ": ", state.status().message()));
  return WriteFileAtomically(path, *state);
}

absl::StatusOr<std::string> Trainer::SerializeState() {
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
    archive.write("critic_learning_rate", torch::tensor(config_.critic_learning_rate, torch::kFloat64));
    archive.write("gamma", torch::tensor(config_.gamma, torch::kFloat64));
    archive.write("lambda", torch::tensor(config_.lambda, torch::kFloat64));
    archive.write("iteration", torch::tensor(static_cast<int64_t>(iteration_)));
    archive.write("env_steps", torch::tensor(static_cast<int64_t>(env_steps_)));
    archive.write("obs_size", torch::tensor(layout_.obs_size));
    archive.write("action_size", torch::tensor(layout_.action_size));
    archive.write("amp_obs_size", torch::tensor(layout_.amp_obs_size));
    archive.write("action_mode", torch::tensor(static_cast<int64_t>(ActionModeOf(config_))));
    archive.write("residual_scale", torch::tensor(config_.residual_scale, torch::kFloat64));
    archive.write("termination_distance", torch::tensor(curriculum_.distance(), torch::kFloat64));
    archive.write("task", c10::IValue(layout_.task));
    if (const PhysicsSettings physics = PhysicsOf(spec_); physics.recorded()) {
      archive.write("physics", c10::IValue(physics.ToJson()));
    }
    archive.write("reference_frames", torch::tensor(static_cast<int64_t>(config_.reference_frames)));
    archive.write("world_size", torch::tensor(static_cast<int64_t>(config_.data_parallel.world_size)));
    archive.write("controller_hidden", torch::tensor(config_.model.controller_hidden, torch::kInt64));
    archive.write("critic_hidden", torch::tensor(config_.model.critic_hidden, torch::kInt64));
    std::ostringstream out(std::ios::binary);
    archive.save_to(out);
    return out.str();
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("cannot write checkpoint: ", message.substr(0, message.find('\n'))));
  }
}

absl::StatusOr<std::unique_ptr<torch::serialize::InputArchive>> LoadCheckpointArchive(const std::string& checkpoint_bytes,
                                                                                      const std::string& origin) {
  try {
    auto archive = std::make_unique<torch::serialize::InputArchive>();
    std::istringstream in(checkpoint_bytes, std::ios::binary);
    archive->load_from(in);
    return archive;
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(
        absl::StrCat(origin, ": not a loadable training checkpoint (different preset or layout?): ",
                     message.substr(0, message.find('\n'))));
  }
}

absl::StatusOr<int64_t> CheckpointAmpObsSize(torch::serialize::InputArchive& checkpoint, const std::string& origin) {
  try {
    torch::Tensor amp_obs_size;
    checkpoint.read("amp_obs_size", amp_obs_size);
    return amp_obs_size.item<int64_t>();
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat(origin, ": ", message.substr(0, message.find('\n'))));
  }
}

namespace {

// A count the checkpoint stores under `key` (`fallback` when it predates the key) against the
// run's --`key`.
absl::Status CheckStoredCount(torch::serialize::InputArchive& archive, const char* key, int64_t fallback,
                              int64_t expected, const std::string& path) {
  torch::Tensor stored = torch::tensor(fallback);
  archive.try_read(key, stored);
  if (stored.item<int64_t>() != expected) {
    return absl::FailedPreconditionError(absl::StrCat(path, ": trained with --", key, " ", stored.item<int64_t>(),
                                                      "; resume with --", key, " ", stored.item<int64_t>(), ", not ",
                                                      expected));
  }
  return absl::OkStatus();
}

// --action_mode and --residual_scale against the checkpoint's; checkpoints from before action
// modes were trained in absolute mode.
absl::Status CheckStoredActionMode(torch::serialize::InputArchive& archive, ActionMode mode, double scale,
                                   const std::string& path) {
  torch::Tensor action_mode = torch::tensor(static_cast<int64_t>(ActionMode::kAbsolute));
  torch::Tensor residual_scale = torch::tensor(scale, torch::kFloat64);
  archive.try_read("action_mode", action_mode);
  archive.try_read("residual_scale", residual_scale);
  const auto trained_mode = static_cast<ActionMode>(action_mode.item<int64_t>());
  if (trained_mode != mode || (trained_mode == ActionMode::kResidual && residual_scale.item<double>() != scale)) {
    return absl::FailedPreconditionError(absl::StrCat(
        path, ": trained with --action_mode ", ActionModeName(trained_mode),
        trained_mode == ActionMode::kResidual ? absl::StrCat(" --residual_scale ", residual_scale.item<double>()) : "",
        "; resume with the same flags"));
  }
  return absl::OkStatus();
}

// Network widths (--controller_hidden, --critic_hidden) against the checkpoint's. Checkpoints
// from before the flags store none and fail later, at the first tensor whose shape differs.
absl::Status CheckStoredWidths(torch::serialize::InputArchive& archive, const ModelConfig& model,
                               const std::string& path) {
  for (const auto& [key, flag, sizes] : {std::tuple{"controller_hidden", "--controller_hidden", &model.controller_hidden},
                                         std::tuple{"critic_hidden", "--critic_hidden", &model.critic_hidden}}) {
    torch::Tensor stored;
    if (!archive.try_read(key, stored)) continue;
    const std::vector<int64_t> trained(stored.data_ptr<int64_t>(), stored.data_ptr<int64_t>() + stored.numel());
    if (trained != *sizes) {
      return absl::FailedPreconditionError(absl::StrCat(path, ": trained with ", flag, " ", absl::StrJoin(trained, ","),
                                                        "; resume with ", flag, " ", absl::StrJoin(trained, ","),
                                                        ", not ", absl::StrJoin(*sizes, ",")));
    }
  }
  return absl::OkStatus();
}

// The physics the run trained under against the server's: a run resumed on a server with another
// --substeps or servo setting would go on training another controller. Checkpoints from before
// the key, and servers from before the field, are not compared.
absl::Status CheckStoredPhysics(torch::serialize::InputArchive& archive, const PhysicsSettings& server,
                                const std::string& path) {
  c10::IValue stored;
  if (!archive.try_read("physics", stored)) return absl::OkStatus();
  if (!stored.isString()) return absl::InvalidArgumentError(absl::StrCat(path, ": physics: not a JSON string"));
  absl::StatusOr<PhysicsSettings> trained = PhysicsSettings::FromJson(stored.toStringRef(), path);
  if (!trained.ok()) return trained.status();
  if (std::string difference = PhysicsDifference(*trained, server, "this server's"); !difference.empty()) {
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": trained with ", difference, "; resume against a server started as the run's was"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status Trainer::LoadCheckpoint(const std::string& path) {
  if (!resume_archive_) {
    auto bytes = ReadFileToString(path, kMaxCheckpointBytes);
    if (!bytes.ok()) return bytes.status();
    auto archive = LoadCheckpointArchive(*bytes, path);
    if (!archive.ok()) return archive.status();
    resume_archive_ = *std::move(archive);
  }
  const absl::Status restored = RestoreState(*resume_archive_, path);
  resume_archive_.reset();  // a checkpoint is megabytes; the run does not need it again
  return restored;
}

void Trainer::RestoreReturnSettings(torch::serialize::InputArchive& archive, const std::string& path) {
  // A run's returns keep one discount across its parts: a resume that left out --gamma would
  // otherwise switch a run trained at another value to the preset's. Data-parallel ranks, which
  // must agree and of which rank 0 alone reads the checkpoint, take them only from the flags.
  for (const auto& [key, given, value, fallback] :
       {std::tuple{"gamma", config_.gamma_given, &config_.gamma, 0.99},
        std::tuple{"lambda", config_.lambda_given, &config_.lambda, 0.95}}) {
    torch::Tensor stored = torch::tensor(fallback, torch::kFloat64);
    archive.try_read(key, stored);
    if (!given && !data_parallel_ && stored.item<double>() != *value) {
      LogLine("%s: the run was trained at --%s %g; resuming with it", path, key, stored.item<double>());
      *value = stored.item<double>();
    }
  }
}

absl::Status Trainer::RestoreState(const std::string& bytes, const std::string& origin) {
  auto archive = LoadCheckpointArchive(bytes, origin);
  return archive.ok() ? RestoreState(**archive, origin) : archive.status();
}

// Whether the checkpoint was trained by a run like this one: its world size, task, reference
// frames, sizes, widths and action mapping.
absl::Status Trainer::CheckCheckpointMatchesRun(torch::serialize::InputArchive& archive, const std::string& path) {
  // Each data-parallel rank's batch is a share of the step's: a run resumes with its world size
  // (checkpoints from before data-parallel runs had one learner).
  if (absl::Status status = CheckStoredCount(archive, "world_size", 1, config_.data_parallel.world_size, path);
      !status.ok()) {
    return status;
  }
  // Checkpoints from before tasks were trackers.
  c10::IValue stored_task{std::string(kTrackingTask)};
  archive.try_read("task", stored_task);
  const std::string task = stored_task.isString() ? stored_task.toStringRef() : "?";
  if (task != layout_.task) {
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": trained for task ", task, "; resume with --task ", task));
  }
  // Before the obs size, which a different count of reference frames changes (checkpoints from
  // before the flag observed one).
  if (absl::Status status = CheckStoredCount(archive, "reference_frames", 1, config_.reference_frames, path);
      !status.ok()) {
    return status;
  }
  torch::Tensor obs_size, action_size, amp_obs_size;
  archive.read("obs_size", obs_size);
  archive.read("action_size", action_size);
  archive.read("amp_obs_size", amp_obs_size);
  if (obs_size.item<int64_t>() != layout_.obs_size || action_size.item<int64_t>() != layout_.action_size ||
      amp_obs_size.item<int64_t>() != layout_.amp_obs_size) {
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": trained with obs ", obs_size.item<int64_t>(), ", actions ", action_size.item<int64_t>(),
                     ", AMP obs ", amp_obs_size.item<int64_t>(), "; the server has ", layout_.obs_size, ", ",
                     layout_.action_size, ", and --amp_frames ", config_.model.amp_frames, " reads ",
                     layout_.amp_obs_size, " AMP floats"));
  }
  if (absl::Status status = CheckStoredWidths(archive, config_.model, path); !status.ok()) return status;
  if (absl::Status status = CheckStoredPhysics(archive, PhysicsOf(spec_), path); !status.ok()) return status;
  if (absl::Status status = CheckStoredActionMode(archive, ActionModeOf(config_), config_.residual_scale, path);
      !status.ok()) {
    return status;
  }
  return absl::OkStatus();
}

absl::Status Trainer::RestoreCriticLearningRate(torch::serialize::InputArchive& archive, const std::string& path) {
  // The critic rate decides the optimizer's groups (two when > 0); checkpoints from before
  // --critic_learning_rate have none: one shared group. A resume without the flag goes on at the
  // checkpoint's rate; data-parallel ranks, which must agree on their optimizers, take it only
  // from the flag.
  torch::Tensor critic_rate = torch::tensor(0.0, torch::kFloat64);
  archive.try_read("critic_learning_rate", critic_rate);
  const double stored_rate = critic_rate.item<double>();
  if (!config_.critic_learning_rate_given && !data_parallel_ && stored_rate != config_.critic_learning_rate) {
    LogLine("%s: the critic was trained at --critic_learning_rate %g; resuming with it", path, stored_rate);
    config_.critic_learning_rate = stored_rate;
    BuildPolicyOptimizer();
  }
  if ((stored_rate > 0) != (config_.critic_learning_rate > 0)) {
    return absl::FailedPreconditionError(absl::StrCat(
        path, ": its optimizer has ", stored_rate > 0 ? 2 : 1, " parameter group(s), trained at --critic_learning_rate ",
        stored_rate, " (0: the critic shared --learning_rate); resume it with that value"));
  }
  return absl::OkStatus();
}

absl::Status Trainer::RestoreState(torch::serialize::InputArchive& archive, const std::string& path) {
  try {
    if (absl::Status status = CheckCheckpointMatchesRun(archive, path); !status.ok()) return status;
    auto load_module = [&](const char* key, torch::nn::Module& module) {
      torch::serialize::InputArchive sub;
      archive.read(key, sub);
      module.load(sub);
    };
    load_module("policy", *policy_);
    load_module("critic", *critic_);
    if (critic_->normalizes_returns() != config_.normalize_value) {
      // The critic's outputs mean what they were trained to mean: the checkpoint decides.
      LogLine("%s: the critic was trained with --normalize_value=%s; resuming with it", path,
              critic_->normalizes_returns() ? "true" : "false");
      config_.normalize_value = critic_->normalizes_returns();
    }
    load_module("discriminator", *discriminator_);
    load_module("obs_norm", *obs_norm_);
    load_module("amp_norm", *amp_norm_);
    if (absl::Status status = RestoreCriticLearningRate(archive, path); !status.ok()) return status;
    RestoreReturnSettings(archive, path);
    torch::serialize::InputArchive optimizer, discriminator_optimizer;
    archive.read("optimizer", optimizer);
    archive.read("discriminator_optimizer", discriminator_optimizer);
    optimizer_->load(optimizer);
    discriminator_optimizer_->load(discriminator_optimizer);
    torch::Tensor iteration, env_steps;
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
  PolicySpec spec = PolicySpecOf(spec_, ActionMapping{ActionModeOf(config_), config_.residual_scale});
  spec.controller_input = ControllerInputName(config_.model.controller_input);
  return learner::ExportPolicy(policy_, obs_norm_, spec, path);
}

}  // namespace modskill::learner
