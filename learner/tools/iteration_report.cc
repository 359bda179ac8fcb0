// modskill-learner's report of each training iteration (iteration_report.h).
#include "learner/tools/iteration_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/log.h"

namespace modskill::learner {
namespace {

// Reward terms with a column: the session's, at most as many as IterationStats keeps.
int NumRewardColumns(const Trainer& trainer) {
  return std::min<int>(trainer.spec().reward_terms_size(), std::size(IterationStats{}.reward_terms));
}

}  // namespace

std::vector<std::string> ProgressColumns(const Trainer& trainer) {
  std::vector<std::string> columns = {"iteration",        "env_steps",       "env_steps_per_second",
                                      "mean_task_reward", "mean_amp_reward", "episode_return",
                                      "episode_length"};
  for (int k = 0; k < NumRewardColumns(trainer); ++k) columns.push_back("reward_" + trainer.spec().reward_terms(k));
  for (const char* column : {"policy_loss", "value_loss", "approx_kl", "clip_fraction", "discriminator_loss",
                             "expert_logit", "policy_logit", "gradient_penalty", "live_sessions", "wall_seconds",
                             "termination_distance", "tracked_share", "collect_seconds", "update_seconds",
                             "policy_lag", "learning_rate"}) {
    columns.push_back(column);
  }
  if (!IsTrackingTask(trainer.config().task)) columns.push_back("normalized_return");
  if (trainer.config().critic_learning_rate > 0) columns.push_back("critic_learning_rate");
  if (!trainer.config().task_teacher.empty()) columns.insert(columns.end(), {"teacher_weight", "teacher_loss"});
  if (trainer.config().data_parallel.world_size > 1) columns.insert(columns.end(), {"allreduce_s", "allreduce_bytes"});
  return columns;
}

std::vector<double> ProgressRow(const IterationStats& s, double elapsed, const Trainer& trainer) {
  std::vector<double> row = {double(s.iteration), double(s.env_steps), s.env_steps_per_second, s.mean_task_reward,
                             s.mean_amp_reward, s.mean_episode_return, s.mean_episode_length};
  for (int k = 0; k < NumRewardColumns(trainer); ++k) row.push_back(s.reward_terms[k]);
  row.insert(row.end(), {s.policy_loss, s.value_loss, s.approx_kl, s.clip_fraction, s.discriminator_loss,
                         s.expert_logit, s.policy_logit, s.gradient_penalty, double(s.live_sessions), elapsed,
                         s.termination_distance, s.tracked_share, s.collect_seconds, s.update_seconds,
                         double(s.policy_lag), s.learning_rate});
  if (!IsTrackingTask(trainer.config().task)) row.push_back(s.normalized_return);
  if (trainer.config().critic_learning_rate > 0) row.push_back(s.critic_learning_rate);
  if (!trainer.config().task_teacher.empty()) row.insert(row.end(), {s.teacher_weight, s.teacher_loss});
  if (trainer.config().data_parallel.world_size > 1) row.insert(row.end(), {s.allreduce_seconds, double(s.allreduce_bytes)});
  return row;
}

void PrintIteration(const IterationStats& s, const Trainer& trainer, int last, double left) {
  std::string terms;
  for (int k = 0; k < NumRewardColumns(trainer); ++k) {
    absl::StrAppendFormat(&terms, "%s%s %.3f", k ? " " : "", trainer.spec().reward_terms(k), s.reward_terms[k]);
  }
  const std::string task = IsTrackingTask(trainer.config().task)
                               ? ""
                               : absl::StrFormat("%s %.3f (%d ended: %s) | ", trainer.config().task,
                                                 s.normalized_return, s.task_episodes, s.task_ends.Summary());
  std::printf(
      "it %4d/%d | %9lld steps %5.0f/s | reward %.3f amp %.3f | return %6.2f len %5.1f | %s%s | "
      "pi %+.4f v %.4f kl %.4f clip %.3f lr %.1e | "
      "D %.3f (expert %+.2f policy %+.2f) | term %.2fm tracked %.2f | sessions %d | collect %.1fs update %.1fs lag %d | "
      "left %s\n",
      s.iteration, last, static_cast<long long>(s.env_steps), s.env_steps_per_second, s.mean_task_reward,
      s.mean_amp_reward, s.mean_episode_return, s.mean_episode_length, task.c_str(), terms.c_str(), s.policy_loss,
      s.value_loss, s.approx_kl, s.clip_fraction, s.learning_rate, s.discriminator_loss, s.expert_logit, s.policy_logit,
      s.termination_distance, s.tracked_share, s.live_sessions, s.collect_seconds, s.update_seconds, s.policy_lag,
      absl::FormatDuration(absl::Seconds(std::round(left))).c_str());
  std::fflush(stdout);
}

void IterationReporter::SkipPassedMilestones() {
  while (next_milestone < milestones.size() && milestones[next_milestone] <= trainer->env_steps()) ++next_milestone;
}

void IterationReporter::Report(const IterationStats& s) {
  const double elapsed = absl::ToDoubleSeconds(absl::Now() - start);
  const double per_iteration = elapsed / std::max(1, s.iteration - first);
  double left = per_iteration * (last - s.iteration);
  if (budget_min > 0) left = std::min(left, std::max(0.0, budget_min * 60 - elapsed));
  PrintIteration(s, *trainer, last, left);
  const std::vector<std::string> columns = ProgressColumns(*trainer);
  const std::vector<double> row = ProgressRow(s, elapsed, *trainer);
  if (budget_min > 0 && elapsed >= budget_min * 60) *stop = true;
  if (events == nullptr) return;
  for (size_t c = 2; c < columns.size(); ++c) (void)events->AddScalar(columns[c], s.env_steps, row[c]);
  (void)events->Flush();
  (void)csv->Append(row);
  ExportMilestones(s);
}

void IterationReporter::ExportMilestones(const IterationStats& s) {
  for (; next_milestone < milestones.size() && s.env_steps >= milestones[next_milestone]; ++next_milestone) {
    const std::string path = absl::StrFormat("%s/policy_at_%gM.pt", trainer->config().run_dir, milestones[next_milestone] / 1e6);
    if (absl::Status exported = trainer->ExportPolicy(path); !exported.ok()) {
      LogLine("milestone policy %s not written: %s", path, exported.message());
    } else {
      LogLine("milestone: %lld env steps, policy exported to %s", static_cast<long long>(s.env_steps), path);
    }
  }
}

}  // namespace modskill::learner
