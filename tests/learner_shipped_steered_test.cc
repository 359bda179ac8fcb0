// The shipped steered skills (data/policies/steered_turns): skills fine-tuned on a reference
// anchored in position only follow a base motion that a goal task turns toward its goal
// (--task_steering_rate). Driven by the skill prior alone, steer's character faces its target
// direction more with the steering on than with the base motion going straight on; the head
// over them earns more than random z. A regression in the steering, the anchoring or the task
// observation shows here on real trained weights.
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "learner/task_checkpoint_evaluation.h"
#include "tests/server_fixture.h"

namespace modskill::learner {
namespace {

const std::string kShipped = std::string(MODSKILL_REPO_DIR) + "/data/policies/steered_turns";

double Term(const TaskEvaluationRow& row, const std::string& name) {
  for (const auto& [term, value] : row.by_term) {
    if (term == name) return value;
  }
  ADD_FAILURE() << "no term " << name;
  return 0;
}

const TaskEvaluationRow* PriorRow(const TaskEvaluationReport& report) {
  for (const TaskEvaluationRow& row : report.rows) {
    if (row.z_source.rfind("the skill prior", 0) == 0) return &row;
  }
  return nullptr;
}

TEST(ShippedSteeredSkillsTest, TheirPriorTurnsWhereTheSteeredBaseMotionPoints) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  TaskCheckpointEvaluation request;
  request.checkpoint = kShipped + "/steer/policy.pt";
  request.skills = kShipped + "/skills/policy.pt";
  request.task = "steer";
  request.motions = {"deepmimic_walk"};
  request.max_episode_steps = 150;
  request.episodes = 8;
  request.seed = 7;
  request.baselines = true;
  auto straight = EvaluateTaskCheckpoint(*client, request);
  ASSERT_TRUE(straight.ok()) << straight.status();
  request.task_settings.set_steering_rate(60);
  auto steered = EvaluateTaskCheckpoint(*client, request);
  ASSERT_TRUE(steered.ok()) << steered.status();
  const TaskEvaluationRow* prior_straight = PriorRow(*straight);
  const TaskEvaluationRow* prior_steered = PriorRow(*steered);
  ASSERT_TRUE(prior_straight && prior_steered) << steered->ToMarkdown();
  EXPECT_GT(Term(*prior_steered, "facing"), 1.3 * Term(*prior_straight, "facing"))
      << straight->ToMarkdown() << steered->ToMarkdown();
  const TaskEvaluationRow& head = steered->rows[0];
  const TaskEvaluationRow& random = steered->rows[1];
  ASSERT_EQ(random.z_source, "random unit z per part, every step");
  EXPECT_GT(head.mean_normalized_return, 2 * random.mean_normalized_return) << steered->ToMarkdown();
}

}  // namespace
}  // namespace modskill::learner
