// Evaluation of a task policy (skill reuse) beside baselines that drive the same frozen skills
// with other z: (a) the trained task policy, deterministic; (b) a uniformly random unit z per
// part, drawn anew every step; (c) one constant z per part, the normalized mean of the z the
// task policy emitted during (a). Each runs one episode in each of `episodes` envs of a Simulate
// session of the task (same seed, so the same start states and goals), reporting the mean
// normalized return (task_return.h).
#ifndef MODSKILL_LEARNER_TASK_EVALUATION_H_
#define MODSKILL_LEARNER_TASK_EVALUATION_H_

#include <string>
#include <utility>
#include <vector>

#include <torch/torch.h>

#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "learner/episode_ends.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/reach_teacher.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

// A task run's exported policy.pt rebuilt as C++ modules (both levels), for driving its skills
// with other z.
struct ImportedTaskPolicy {
  ModSkillPolicy policy{nullptr};
  RunningMeanStd obs_norm{nullptr};
};

// INVALID_ARGUMENT naming `path` unless it is a task policy for `task_spec`'s task, parts and
// sizes (a tracker's policy.pt is refused, naming its task).
absl::StatusOr<ImportedTaskPolicy> ImportTaskPolicy(const std::string& path, const v1::EnvSpec& task_spec);

struct TaskEvaluationRow {
  std::string z_source;  // what drove the skills
  double mean_normalized_return = 0;
  double mean_episode_length = 0;  // steps
  int episodes = 0;
  EpisodeEnds ends;  // why they ended (empty where the server does not say)
  // Each goal term's part of the mean normalized return (they add up to it), e.g. strike's tip
  // term against its approach term: what the return was earned by.
  std::vector<std::pair<std::string, double>> by_term;
};

struct TaskEvaluationReport {
  std::string task, checkpoint;
  int episode_steps = 0;  // what returns are normalized by
  std::vector<TaskEvaluationRow> rows;  // the task policy first

  std::string ToJson() const;
  std::string ToMarkdown() const;
};

struct TaskEvaluationOptions {
  v1::SessionConfig session;  // task, part layout, action mapping, motions; num_envs and seed are set here
  int episodes = 32;          // one per env
  uint64_t seed = 1;
  bool baselines = true;      // (b) and (c) beside (a)
  int max_steps = 100000;     // a session step limit, against episodes that never end
  // Reach: a row for the teacher itself (--task_teacher): its nearest held pose's z on
  // `teacher_parts` ([P], 1 where supervised), the skill prior's on the others.
  const ReachTeacher* teacher = nullptr;
  torch::Tensor teacher_parts;
};

absl::StatusOr<TaskEvaluationReport> EvaluateTaskPolicy(SimulationClient& client, ImportedTaskPolicy& imported,
                                                        const std::string& checkpoint_name,
                                                        const TaskEvaluationOptions& options);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TASK_EVALUATION_H_
