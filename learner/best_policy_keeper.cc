#include "learner/best_policy_keeper.h"

#include <filesystem>
#include <system_error>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "common/policy/policy_checkpoint.h"

namespace modskill::learner {
namespace {

PolicyScore ScoreOf(const EvaluationReport& report, int iteration, int64_t env_steps) {
  return PolicyScore{report.success_rate, report.mpjpe_mm, report.g_mpjpe_mm, iteration, env_steps};
}

// A score read back at a resume has no iteration (0): the run before the resume made it.
std::string Describe(const PolicyScore& score) {
  const std::string when = score.iteration > 0 ? absl::StrFormat("iteration %d, %.2f M steps", score.iteration,
                                                                 score.env_steps / 1e6)
                                               : "before the resume";
  return absl::StrFormat("Succ %.0f %%, E_mpjpe %.1f mm, E_g-mpjpe %.1f mm (%s)", 100 * score.success_rate,
                         score.mpjpe_mm, score.g_mpjpe_mm, when);
}

}  // namespace

bool PolicyScore::BetterThan(const PolicyScore& other) const {
  if (success_rate != other.success_rate) return success_rate > other.success_rate;
  return mpjpe_mm + g_mpjpe_mm < other.mpjpe_mm + other.g_mpjpe_mm;
}

absl::Status BestPolicyKeeper::CheckSettings(const TrainerConfig& config, int every) {
  if (every < 1) return absl::InvalidArgumentError(absl::StrCat("--keep_best_every: ", every, " is not >= 1"));
  if (!IsTrackingTask(config.task)) {
    return absl::InvalidArgumentError(absl::StrCat("--keep_best_every: a ", config.task,
                                                   " run has no clip to evaluate against; it keeps trackers only"));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<BestPolicyKeeper>> BestPolicyKeeper::Create(const Trainer& trainer,
                                                                           SimulationClient* client, int every) {
  const TrainerConfig& config = trainer.config();
  if (absl::Status settings = CheckSettings(config, every); !settings.ok()) return settings;
  auto curve = CsvLogger::Open(config.run_dir + "/evaluations.csv",
                               {"iteration", "env_steps", "success_rate", "mpjpe_mm", "g_mpjpe_mm", "kept"},
                               config.resume ? CsvLogger::Start::kAppend : CsvLogger::Start::kFresh);
  if (!curve.ok()) return curve.status();
  std::unique_ptr<BestPolicyKeeper> keeper(
      new BestPolicyKeeper(client, every, config.run_dir, config.motions, *std::move(curve)));
  const std::string path = keeper->best_path();
  std::error_code error;
  if (!config.resume) {
    std::filesystem::remove(path, error);
    for (const char* report : {"/policy_best.md", "/policy_best.json"}) std::filesystem::remove(config.run_dir + report, error);
    return keeper;
  }
  if (!std::filesystem::exists(path, error)) return keeper;
  absl::StatusOr<EvaluationReport> report = keeper->EvaluateFile(path);
  if (!report.ok()) {
    // A kept file this server cannot evaluate (its clips changed, say) has no score to defend:
    // the run's next evaluation replaces it.
    LogLine("warning: %s is not evaluated again (%s); the next evaluation replaces it", path, report.status().message());
    return keeper;
  }
  keeper->best_ = ScoreOf(*report, 0, 0);
  LogLine("best policy so far (%s): %s", path, Describe(*keeper->best_));
  return keeper;
}

absl::StatusOr<EvaluationReport> BestPolicyKeeper::EvaluateFile(const std::string& path) {
  absl::StatusOr<std::string> bytes = ReadFileToString(path, kMaxPolicyFileBytes);
  if (!bytes.ok()) return bytes.status();
  return Evaluate(*client_, path, *bytes, clips_);
}

absl::Status BestPolicyKeeper::AfterIteration(Trainer& trainer) {
  if (trainer.iteration() % every_ != 0) return absl::OkStatus();
  const absl::Time start = absl::Now();
  const std::string candidate = run_dir_ + "/policy_candidate.pt";
  if (absl::Status exported = trainer.ExportPolicy(candidate); !exported.ok()) return exported;
  absl::StatusOr<EvaluationReport> report = EvaluateFile(candidate);
  std::error_code error;
  if (!report.ok()) {
    std::filesystem::remove(candidate, error);
    return report.status();
  }
  const PolicyScore score = ScoreOf(*report, trainer.iteration(), trainer.env_steps());
  scores_.push_back(score);
  const bool better = !best_ || score.BetterThan(*best_);
  if (!better) {
    std::filesystem::remove(candidate, error);
  } else {
    // The reports first: a policy_best.pt is never newer than the files that score it.
    const std::string json = absl::StrFormat(R"({"iteration": %d, "env_steps": %d, "evaluation": %s})",
                                             score.iteration, score.env_steps, report->ToJson());
    const std::string table = report->ToMarkdown(absl::StrCat("policy_best.pt: ", Describe(score)));
    for (const auto& [name, text] : {std::pair<std::string, std::string>{"policy_best.json", json},
                                     {"policy_best.md", table}}) {
      if (absl::Status written = WriteFileAtomically(run_dir_ + "/" + name, text); !written.ok()) return written;
    }
    std::filesystem::rename(candidate, best_path(), error);
    if (error) return absl::InternalError(absl::StrCat(best_path(), ": ", error.message()));
    best_ = score;
  }
  if (absl::Status row = curve_->Append({static_cast<double>(score.iteration), static_cast<double>(score.env_steps),
                                          score.success_rate, score.mpjpe_mm, score.g_mpjpe_mm, better ? 1.0 : 0.0});
      !row.ok()) {
    return row;
  }
  LogLine("evaluated: %s in %.1f s; %s", Describe(score), absl::ToDoubleSeconds(absl::Now() - start),
          better ? "kept as policy_best.pt" : absl::StrCat("best stays ", Describe(*best_)));
  return absl::OkStatus();
}

}  // namespace modskill::learner
