// The shipped strike policy (data/policies/strike_turns): its head, over the frozen turning walk
// skills it was trained on, earns more of strike's return than random z from the same start
// states and keeps the character up longer. A regression in the strike env, the task observation
// or policy import shows here on real trained weights.
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "learner/task_checkpoint_evaluation.h"
#include "tests/server_fixture.h"

namespace modskill::learner {
namespace {

const std::string kShipped = std::string(MODSKILL_REPO_DIR) + "/data/policies/strike_turns";

// The shipped head evaluated as data/policies/README.md evaluates it (modskill-learner --eval
// --task strike), on a server that holds its clip.
class ShippedStrikePolicyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = StartTestServer();
    client_ = ConnectTo(*server_);
    auto added = client_->AddMotionFiles({kShipped + "/motions/walk_arm_forward.msclip"});
    ASSERT_TRUE(added.ok()) << added.status();
    request_.checkpoint = kShipped + "/head/policy.pt";
    request_.task = "strike";
    request_.motions = {"walk_arm_forward"};
    request_.skills = kShipped + "/skills/policy.pt";
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
  TaskCheckpointEvaluation request_;
};

TEST_F(ShippedStrikePolicyTest, ItsHeadEarnsMoreThanRandomZAndStaysUpLonger) {
  TaskCheckpointEvaluation request = request_;
  request.max_episode_steps = 120;
  request.episodes = 8;
  request.seed = 7;
  request.baselines = true;
  auto report = EvaluateTaskCheckpoint(*client_, request);
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
TEST_F(ShippedStrikePolicyTest, OtherSkillsThanTheHeadsAreRefused) {
  TaskCheckpointEvaluation request = request_;
  request.skills = std::string(MODSKILL_REPO_DIR) + "/data/policies/walk_proprio_loop/policy.pt";
  request.episodes = 2;
  auto report = EvaluateTaskCheckpoint(*client_, request);
  ASSERT_FALSE(report.ok());
  EXPECT_NE(report.status().message().find("skills"), std::string::npos) << report.status();
}

}  // namespace
}  // namespace modskill::learner
