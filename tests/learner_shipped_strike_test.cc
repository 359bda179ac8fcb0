// The shipped strike policy (data/policies/strike_turns): its head, over the frozen turning walk
// skills it was trained on, earns more of strike's return than random z from the same start
// states and keeps the character up longer. A regression in the strike env, the task observation
// or policy import shows here on real trained weights.
#include <string>

#include <gtest/gtest.h>

#include "learner/task_checkpoint_evaluation.h"
#include "tests/server_fixture.h"

namespace modskill::learner {
namespace {

const std::string kShipped = std::string(MODSKILL_REPO_DIR) + "/data/policies/strike_turns";

TEST(ShippedStrikePolicyTest, ItsHeadEarnsMoreThanRandomZAndStaysUpLonger) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  auto added = client->AddMotionFiles({kShipped + "/motions/walk_arm_forward.msclip"});
  ASSERT_TRUE(added.ok()) << added.status();
  // As data/policies/README.md evaluates it (modskill-learner --eval --task strike), shorter.
  TaskCheckpointEvaluation request;
  request.checkpoint = kShipped + "/head/policy.pt";
  request.task = "strike";
  request.motions = {"walk_arm_forward"};
  request.skills = kShipped + "/skills/policy.pt";
  request.max_episode_steps = 120;
  request.episodes = 8;
  request.seed = 7;
  request.baselines = true;
  auto report = EvaluateTaskCheckpoint(*client, request);
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_GE(report->rows.size(), 2u);
  const TaskEvaluationRow& head = report->rows[0];
  const TaskEvaluationRow& random = report->rows[1];
  ASSERT_EQ(random.z_source, "random unit z per part, every step");
  EXPECT_GT(head.mean_normalized_return, 1.5 * random.mean_normalized_return)
      << report->ToMarkdown();
  EXPECT_GT(head.mean_episode_length, 1.5 * random.mean_episode_length) << report->ToMarkdown();
}

// Skills the head was not trained over are refused before any episode runs, naming --skills.
TEST(ShippedStrikePolicyTest, OtherSkillsThanTheHeadsAreRefused) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  auto added = client->AddMotionFiles({kShipped + "/motions/walk_arm_forward.msclip"});
  ASSERT_TRUE(added.ok()) << added.status();
  TaskCheckpointEvaluation request;
  request.checkpoint = kShipped + "/head/policy.pt";
  request.task = "strike";
  request.motions = {"walk_arm_forward"};
  request.skills = std::string(MODSKILL_REPO_DIR) + "/data/policies/walk_proprio_loop/policy.pt";
  request.episodes = 2;
  auto report = EvaluateTaskCheckpoint(*client, request);
  ASSERT_FALSE(report.ok());
  EXPECT_NE(report.status().message().find("skills"), std::string::npos) << report.status();
}

}  // namespace
}  // namespace modskill::learner
