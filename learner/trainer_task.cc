// A task run's set-up (skill reuse): the skills it reuses, the check that the server offers the
// task, the frozen controllers and self-feature statistics, and the task's episode figure.
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "common/log.h"
#include "learner/server_discovery.h"
#include "learner/task_parts.h"
#include "learner/trainer.h"
#include "learner/trainer_phases.h"

namespace modskill::learner {
namespace {

// Describe's tracking spec for `config`'s part layout from the first server, retried (like
// WaitForServers) until config.server_timeout_s while the server is not up.
absl::StatusOr<v1::EnvSpec> DescribeFirstServer(const TrainerConfig& config) {
  absl::StatusOr<std::string> first = FirstServerTarget(config.servers);
  if (!first.ok()) return first.status();
  ClientOptions options;
  options.server = *first;
  options.token = config.token;
  options.tls_ca_file = config.tls_ca_file;
  options.connect_timeout = absl::Seconds(3);
  const absl::Time deadline = absl::Now() + absl::Seconds(config.server_timeout_s);
  while (true) {
    auto client = SimulationClient::Connect(options);
    absl::StatusOr<v1::EnvSpec> spec = client.ok() ? (*client)->Describe(config.part_layout)
                                                   : absl::StatusOr<v1::EnvSpec>(client.status());
    const bool retry = !spec.ok() && (spec.status().code() == absl::StatusCode::kUnavailable ||
                                      spec.status().code() == absl::StatusCode::kDeadlineExceeded);
    if (!retry) return spec;
    if (absl::Now() > deadline) {
      return absl::UnavailableError(absl::StrCat("--task ", config.task, ": no answer to Describe from ",
                                                 options.server, " (--server_timeout_s): ", spec.status().message()));
    }
    absl::SleepFor(absl::Milliseconds(500));
  }
}

}  // namespace

absl::Status Trainer::PrepareTask() {
  auto skills = SkillLibrary::Load(config_.skills);
  if (!skills.ok()) return absl::Status(skills.status().code(), absl::StrCat("--skills: ", skills.status().message()));
  skills_ = *std::move(skills);
  // The controllers act through the action mapping they were trained with.
  config_.action_mode = ActionModeName(skills_->spec().action.mode);
  config_.residual_scale = skills_->spec().action.residual_scale;
  auto tracking = DescribeFirstServer(config_);
  if (!tracking.ok()) return tracking.status();
  tracking_spec_ = *std::move(tracking);
  return CheckTaskOffered(tracking_spec_, config_.task, config_.servers.front());
}

absl::Status Trainer::LoadSkills() {
  if (absl::Status status = skills_->LoadControllers(*policy_); !status.ok()) return status;
  if (absl::Status status = skills_->LoadSelfStatistics(tracking_spec_, spec_, *obs_norm_); !status.ok()) return status;
  if (!config_.task_parts.empty()) {
    auto mask = RestrictTaskHeadToParts(*policy_, config_.task_parts, config_.part_layout);
    if (!mask.ok()) return mask.status();
    sampled_dims_ = *std::move(mask);
  }
  if (!config_.task_teacher.empty()) {
    auto teacher = ReachTeacher::Load(config_.task_teacher);
    if (!teacher.ok()) return teacher.status();
    auto mask = teacher->PartMask(policy_->layout(), policy_->config().embed_dim, config_.task_parts);
    if (!mask.ok()) return mask.status();
    teacher_ = *std::move(teacher);
    teacher_parts_ = *std::move(mask);
    LogLine("task reach: teacher of %d held poses from %s, weight %g%s", static_cast<int>(teacher_->size()),
            config_.task_teacher, config_.task_teacher_weight,
            config_.task_teacher_steps > 0 ? absl::StrCat(" falling to 0 over ", config_.task_teacher_steps, " steps") : "");
  }
  task_return_.emplace(std::vector<std::string>(spec_.reward_terms().begin(), spec_.reward_terms().end()),
                       /*max_episode_steps=*/0);
  LogLine("task %s: %d frozen part controllers from %s (z of %d, %s actions); task head %s, %s%s", config_.task,
          static_cast<int>(skills_->num_parts()), skills_->path(), static_cast<int>(skills_->embed_dim()),
          config_.action_mode, absl::StrJoin(config_.model.task_hidden, "x"),
          policy_->uses_skill_prior() ? "displacing the tracker's z on the base motion (skill prior)"
                                      : "z from the head alone",
          config_.task_parts.empty() ? "" : absl::StrCat(" of ", absl::StrJoin(config_.task_parts, ","), " only"));
  return absl::OkStatus();
}

void Trainer::SummarizeTaskEpisodes(const Collection& collection, IterationStats* stats) const {
  if (!task_return_) return;
  std::vector<double> ended;
  for (const SlotRollout& r : collection.rollouts) {
    ended.insert(ended.end(), r.normalized_returns.begin(), r.normalized_returns.end());
    stats->task_ends.Merge(r.ends);
  }
  stats->normalized_return = MeanOrNan(ended);
  stats->task_episodes = static_cast<int>(ended.size());
}

}  // namespace modskill::learner
