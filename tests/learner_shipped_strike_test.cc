// The shipped strike policy (data/policies/strike_turns): its head, over the frozen turning walk
// skills it was trained on, earns more of strike's return than random z from the same start
// states and keeps the character up longer. A regression in the strike env, the task observation
// or policy import shows here on real trained weights.
#include <string>

#include <gtest/gtest.h>

#include "learner/policy_import.h"
#include "learner/task_evaluation.h"
#include "tests/server_fixture.h"

namespace modskill::learner {
namespace {

const std::string kShipped = std::string(MODSKILL_REPO_DIR) + "/data/policies/strike_turns";

TEST(ShippedStrikePolicyTest, ItsHeadEarnsMoreThanRandomZAndStaysUpLonger) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  auto added = client->AddMotionFiles({kShipped + "/motions/walk_arm_forward.msclip"});
  ASSERT_TRUE(added.ok()) << added.status();
  auto exported = ReadExportedPolicy(kShipped + "/head/policy.pt");
  ASSERT_TRUE(exported.ok()) << exported.status();
  ASSERT_EQ(exported->spec.action.mode, ActionMode::kResidual);

  TaskEvaluationOptions options;
  options.session.set_task("strike");
  options.session.add_motions("walk_arm_forward");
  options.session.set_action_mode(v1::RESIDUAL);
  options.session.set_residual_scale(static_cast<float>(exported->spec.action.residual_scale));
  options.session.set_termination(v1::EVALUATION);
  options.session.set_max_episode_steps(120);
  options.episodes = 8;
  options.seed = 7;
  v1::SessionConfig probe = options.session;
  probe.set_num_envs(1);
  auto stream = client->OpenSession(probe);
  ASSERT_TRUE(stream.ok()) << stream.status();
  const v1::EnvSpec spec = (*stream)->spec();
  (void)(*stream)->Close();

  auto imported = ImportTaskPolicy(kShipped + "/head/policy.pt", spec);
  ASSERT_TRUE(imported.ok()) << imported.status();
  auto report = EvaluateTaskPolicy(*client, *imported, "strike_turns", options);
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_GE(report->rows.size(), 2u);
  const TaskEvaluationRow& head = report->rows[0];
  const TaskEvaluationRow& random = report->rows[1];
  ASSERT_EQ(random.z_source, "random unit z per part, every step");
  EXPECT_GT(head.mean_normalized_return, 1.5 * random.mean_normalized_return)
      << report->ToMarkdown();
  EXPECT_GT(head.mean_episode_length, 1.5 * random.mean_episode_length) << report->ToMarkdown();
}

}  // namespace
}  // namespace modskill::learner
