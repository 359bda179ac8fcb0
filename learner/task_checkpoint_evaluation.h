// What `modskill-learner --eval --task` does, as a library call: a task run's policy.pt evaluated
// on a server, its session built from what the checkpoint records (layout, action mapping) and
// the request (task, clips, goal settings), beside the baselines. Tests call it on shipped
// policies exactly as the CLI does.
#ifndef MODSKILL_LEARNER_TASK_CHECKPOINT_EVALUATION_H_
#define MODSKILL_LEARNER_TASK_CHECKPOINT_EVALUATION_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "learner/task_evaluation.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

struct TaskCheckpointEvaluation {
  std::string checkpoint;  // a task run's policy.pt (both levels)
  std::string task;        // steer, reach, strike or vr_tracking
  std::vector<std::string> motions;  // the sessions' clips (empty: the server's library)
  v1::TaskSettings task_settings;    // goal ranges (0 in a field: its default)
  int max_episode_steps = 0;         // 0: the task's (300 steps)
  int episodes = 32;
  uint64_t seed = 1;
  bool baselines = false;  // random z, constant z and the skill prior beside the policy
  // Optional: the skills the head must have been trained over (--skills): refused, naming it,
  // when its controllers are not the checkpoint's.
  std::string skills;
  // Optional, reach with a skill prior and baselines: a row for a teacher table (--task_teacher)
  // over `task_parts` (empty: every part).
  std::string teacher;
  std::vector<std::string> task_parts;
};

// FAILED_PRECONDITION when the server does not offer the task or the skills do not fit; the
// import's and the session's errors otherwise, each naming what it refuses.
absl::StatusOr<TaskEvaluationReport> EvaluateTaskCheckpoint(SimulationClient& client,
                                                            const TaskCheckpointEvaluation& request);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TASK_CHECKPOINT_EVALUATION_H_
