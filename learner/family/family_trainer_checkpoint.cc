// FamilyTrainer's files: checkpoint.pt (networks, optimizers, counters and the elite set, written
// atomically), parameterization.pt, and progress.csv (one row per iteration).
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "common/atomic_file.h"
#include "common/wire/policy_spec_wire.h"
#include "learner/family/family_export.h"
#include "learner/family/family_trainer.h"

namespace modskill::learner::family {
namespace {

constexpr size_t kMaxCheckpointBytes = size_t{1} << 30;

// The parameter ranges as text: a resumed run must train the same family.
std::string RangesKey(const std::vector<ParamRange>& ranges, const std::string& clip) {
  std::vector<std::string> parts = {clip};
  for (const ParamRange& range : ranges) parts.push_back(absl::StrCat(range.name, "=", range.lo, ":", range.hi));
  return absl::StrJoin(parts, " ");
}

std::string Serialize(torch::serialize::OutputArchive& archive) {  // save_to is not const
  std::ostringstream out;
  archive.save_to(out);
  return out.str();
}

}  // namespace

absl::Status FamilyTrainer::SaveCheckpoint() const {
  try {
    torch::serialize::OutputArchive archive, model, optimizer, net, net_optimizer;
    model_->save(model);
    optimizer_->save(optimizer);
    net_->save(net);
    net_optimizer_->save(net_optimizer);
    archive.write("model", model);
    archive.write("optimizer", optimizer);
    archive.write("parameterization", net);
    archive.write("parameterization_optimizer", net_optimizer);
    const std::string key = RangesKey(config_.ranges, config_.clip);
    archive.write("family", torch::from_blob(const_cast<char*>(key.data()), {static_cast<int64_t>(key.size())},
                                             torch::kChar).clone());
    archive.write("counters", torch::tensor({static_cast<int64_t>(iteration_), env_steps_,
                                             static_cast<int64_t>(wall_s_ * 1000)}));
    archive.write("learning_rate", torch::tensor({learning_rate_->rate()}, torch::kDouble));
    std::vector<torch::Tensor> params, fitness, trajectories;
    for (int64_t id : elites_->Ids()) {
      const Elite& elite = elites_->elite(id);
      params.push_back(torch::tensor(elite.params, torch::kDouble));
      fitness.push_back(torch::tensor(elite.fitness, torch::kDouble));
      trajectories.push_back(elite.trajectory);
    }
    if (!params.empty()) {
      archive.write("elite_params", torch::stack(params));
      archive.write("elite_fitness", torch::stack(fitness));
      archive.write("elite_trajectories", torch::stack(trajectories));
    }
    if (absl::Status status = WriteFileAtomically(config_.run_dir + "/parameterization.pt", Serialize(net));
        !status.ok()) {
      return status;
    }
    return WriteFileAtomically(config_.run_dir + "/checkpoint.pt", Serialize(archive));
  } catch (const c10::Error& e) {
    return absl::InternalError(absl::StrCat("checkpoint: ", e.what_without_backtrace()));
  }
}

absl::Status FamilyTrainer::ExportPolicyFile() {
  const v1::EnvSpec& env = stream_->spec();
  ActionMapping residual;
  residual.mode = ActionMode::kResidual;
  residual.residual_scale = config_.residual_scale;
  modskill::PolicySpec spec = PolicySpecOf(env, residual);
  // What a family's file has always recorded, whatever a server says: the tracking task on one
  // reference frame (its observation is the family env's own, family_export.h).
  spec.task = kTrackingTask;
  spec.reference_frames = 1;
  spec.family_clip = config_.clip;
  spec.family_frames = frames_;
  spec.family = config_.ranges;
  return ExportFamilyPolicy(*model_, net_fitted_ ? net_.get() : nullptr, *elites_, *space_, spec,
                            config_.run_dir + "/policy.pt");
}

absl::Status FamilyTrainer::LoadCheckpoint() {
  const std::string path = config_.run_dir + "/checkpoint.pt";
  auto bytes = ReadFileToString(path, kMaxCheckpointBytes);
  if (!bytes.ok()) return absl::NotFoundError(absl::StrCat("--resume: ", bytes.status().message()));
  try {
    torch::serialize::InputArchive archive, model, optimizer, net, net_optimizer;
    archive.load_from(bytes->data(), bytes->size());
    torch::Tensor family, counters;
    archive.read("family", family);
    const std::string key(static_cast<const char*>(family.data_ptr()), family.numel());
    if (key != RangesKey(config_.ranges, config_.clip)) {
      return absl::FailedPreconditionError(absl::StrCat("--resume: ", path, " trained the family '", key,
                                                        "', not '", RangesKey(config_.ranges, config_.clip), "'"));
    }
    archive.read("model", model);
    archive.read("optimizer", optimizer);
    archive.read("parameterization", net);
    archive.read("parameterization_optimizer", net_optimizer);
    model_->load(model);
    optimizer_->load(optimizer);
    net_->load(net);
    net_optimizer_->load(net_optimizer);
    archive.read("counters", counters);
    iteration_ = static_cast<int>(counters[0].item<int64_t>());
    env_steps_ = counters[1].item<int64_t>();
    wall_s_ = counters[2].item<int64_t>() / 1000.0;
    // Checkpoints from before the KL-steered rate have none: the configured rate then.
    if (torch::Tensor rate; archive.try_read("learning_rate", rate)) learning_rate_->set_rate(rate.item<double>());
    learning_rate_->ApplyTo(*optimizer_);
    torch::Tensor params, fitness, trajectories;
    if (archive.try_read("elite_params", params)) {
      archive.read("elite_fitness", fitness);
      archive.read("elite_trajectories", trajectories);
      for (int64_t e = 0; e < params.size(0); ++e) {
        const std::vector<double> a(params[e].data_ptr<double>(), params[e].data_ptr<double>() + params.size(1));
        if (auto entered = elites_->Offer(a, fitness[e].item<double>(), trajectories[e]); !entered.ok()) {
          return entered.status();
        }
        // The visit density restarts from the elites' parameters (it is not saved).
        if (absl::Status status = curriculum_->AddVisited(a); !status.ok()) return status;
      }
    }
  } catch (const c10::Error& e) {
    return absl::DataLossError(absl::StrCat("--resume: ", path, ": ", e.what_without_backtrace()));
  }
  return absl::OkStatus();
}

const std::vector<std::string>& FamilyProgressColumns() {
  static const std::vector<std::string> columns = {
      "iteration", "env_steps", "wall_s",    "episodes",        "mean_return",      "mean_length",
      "mean_fitness", "elites",  "coverage", "curriculum_mode", "exploration_rate", "net_loss",
      "approx_kl", "learning_rate", "action_std"};
  return columns;
}

absl::Status FamilyTrainer::AppendProgress(const FamilyIterationStats& s) {
  return progress_->AppendCells({absl::StrCat(s.iteration), absl::StrCat(s.env_steps), absl::StrFormat("%.1f", s.wall_s),
                                 absl::StrCat(s.episodes), absl::StrFormat("%.4f", s.mean_return),
                                 absl::StrFormat("%.2f", s.mean_length), absl::StrFormat("%.4f", s.mean_fitness),
                                 absl::StrCat(s.elites), absl::StrFormat("%.4f", s.coverage), s.mode,
                                 absl::StrFormat("%.4f", s.exploration_rate), absl::StrFormat("%.6f", s.net_loss),
                                 absl::StrFormat("%.6f", s.approx_kl), absl::StrFormat("%.3g", s.learning_rate),
                                 absl::StrFormat("%.4f", s.action_std)});
}

}  // namespace modskill::learner::family
