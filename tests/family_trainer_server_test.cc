// The family trainer end to end against an in-process server: iterations run, episodes reach the
// elite set with the server's fitness, progress.csv and the checkpoint are written, a resumed run
// continues the counters and the KL-steered learning rate and refuses another family; bad flags name themselves.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "learner/family/family_trainer.h"
#include "tests/family_test_config.h"
#include "tests/server_fixture.h"

namespace modskill::learner::family {
namespace {

FamilyTrainerConfig SmallFamily(const RunningServer& server, const std::string& run_dir) {
  return SmallFamilyConfig(server.port(), run_dir);
}

int CountLines(const std::string& path) {
  std::ifstream in(path);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  return lines;
}

TEST(FamilyTrainerTest, TrainsWritesAndResumes) {
  auto server = StartTestServer();
  ASSERT_NE(server, nullptr);
  const std::string run_dir = std::string(MODSKILL_TEST_TMP_DIR) + "/family_trainer";
  std::filesystem::remove_all(run_dir);
  FamilyTrainerConfig config = SmallFamily(*server, run_dir);
  config.max_iterations = 2;
  double rate_at_stop = 0;
  {
    auto trainer = FamilyTrainer::Create(config);
    ASSERT_TRUE(trainer.ok()) << trainer.status();
    HurryThroughTheClip(**trainer);
    ASSERT_TRUE((*trainer)->Run([] { return false; }).ok());
    EXPECT_EQ((*trainer)->env_steps(), 2 * 8 * 48);
    // 96 steps of the 38-frame walk: episodes that reached the clip's end were offered.
    EXPECT_GT((*trainer)->elites().size(), 0);
    for (int64_t id : (*trainer)->elites().Ids()) {
      const Elite& elite = (*trainer)->elites().elite(id);
      EXPECT_GT(elite.fitness, 0.0);
      EXPECT_EQ(elite.trajectory.size(1), 70);  // 69 displacements and tau
    }
    // The KL of a fresh policy's steps is far from the target: the rate moved, within its bounds.
    rate_at_stop = (*trainer)->learning_rate();
    EXPECT_NE(rate_at_stop, config.learning_rate);
    EXPECT_GE(rate_at_stop, KlAdaptiveLearningRate::kMinRate);
  }
  EXPECT_EQ(CountLines(run_dir + "/progress.csv"), 1 + 2);
  EXPECT_TRUE(std::filesystem::exists(run_dir + "/checkpoint.pt"));
  EXPECT_TRUE(std::filesystem::exists(run_dir + "/parameterization.pt"));

  config.resume = true;
  config.max_iterations = 1;
  auto resumed = FamilyTrainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ((*resumed)->env_steps(), 2 * 8 * 48);
  EXPECT_DOUBLE_EQ((*resumed)->learning_rate(), rate_at_stop) << "the steered rate is part of the checkpoint";
  auto evaluated = (*resumed)->Evaluate({{4.0}, {14.0}});
  ASSERT_TRUE(evaluated.ok()) << evaluated.status();
  ASSERT_EQ(evaluated->size(), 2u);
  EXPECT_EQ((*evaluated)[1].params, std::vector<double>{14.0});
  for (const FamilyRolloutResult& episode : *evaluated) {
    EXPECT_GT(episode.steps, 0);
    EXPECT_GT(episode.apex_height, 0.5);  // the pelvis stands at about 0.9 m
    EXPECT_GT(episode.highest_effector, 0.5);  // a walker's wrists hang at about 0.8 m
    EXPECT_LT(episode.highest_effector, 2.0);
    EXPECT_GE(episode.flight_s, 0.0);
  }
  EXPECT_EQ((*resumed)->Evaluate({{20.0}}).status().code(), absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE((*resumed)->Run([] { return false; }).ok());
  EXPECT_EQ(CountLines(run_dir + "/progress.csv"), 1 + 3);

  FamilyTrainerConfig other = config;
  other.ranges = {{"gravity", 5, 14}};
  auto refused = FamilyTrainer::Create(other);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(refused.status().message().find("gravity=4:14"), std::string::npos) << refused.status();

  // A fresh run in the used directory starts its own curve instead of drawing after the old one.
  FamilyTrainerConfig fresh = config;
  fresh.resume = false;
  auto restarted = FamilyTrainer::Create(fresh);
  ASSERT_TRUE(restarted.ok()) << restarted.status();
  EXPECT_EQ(CountLines(run_dir + "/progress.csv"), 1) << "the header alone";
}

TEST(FamilyTrainerTest, PpoRatiosCompareTheInputsTheBehaviourPolicySaw) {
  // With a vanishing learning rate the policy does not move, so each update's KL must be ~0. It was
  // 0.02 and more when the observation statistics absorbed the batch before the epochs: the same
  // weights then saw differently normalized inputs than when they acted.
  auto server = StartTestServer();
  ASSERT_NE(server, nullptr);
  const std::string run_dir = std::string(MODSKILL_TEST_TMP_DIR) + "/family_still";
  std::filesystem::remove_all(run_dir);
  FamilyTrainerConfig config = SmallFamily(*server, run_dir);
  config.learning_rate = 1e-9;
  config.target_kl = 0;
  auto trainer = FamilyTrainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  for (int i = 0; i < 3; ++i) {
    auto stats = (*trainer)->Iterate();
    ASSERT_TRUE(stats.ok()) << stats.status();
    EXPECT_LT(stats->approx_kl, 1e-5) << "iteration " << i;
  }
}

TEST(FamilyTrainerTest, BadSettingsAreNamed) {
  auto server = StartTestServer();
  ASSERT_NE(server, nullptr);
  FamilyTrainerConfig config = SmallFamily(*server, std::string(MODSKILL_TEST_TMP_DIR) + "/family_bad");
  config.clip = "no_such_clip";
  auto missing = FamilyTrainer::Create(config);
  EXPECT_NE(missing.status().message().find("no_such_clip"), std::string::npos) << missing.status();
  config = SmallFamily(*server, std::string(MODSKILL_TEST_TMP_DIR) + "/family_bad");
  config.ranges = {{"leg_scale", 1.2, 0.8}};
  auto inverted = FamilyTrainer::Create(config);
  EXPECT_NE(inverted.status().message().find("leg_scale"), std::string::npos) << inverted.status();
  config = SmallFamily(*server, std::string(MODSKILL_TEST_TMP_DIR) + "/family_bad");
  config.horizon = 1;
  EXPECT_NE(FamilyTrainer::Create(config).status().message().find("--horizon"), std::string::npos);
  config = SmallFamily(*server, std::string(MODSKILL_TEST_TMP_DIR) + "/family_bad");
  config.target_kl = -0.1;
  EXPECT_NE(FamilyTrainer::Create(config).status().message().find("--family_target_kl"), std::string::npos);
  for (double distance : {-1.0, std::nan(""), 1e9}) {
    config = SmallFamily(*server, std::string(MODSKILL_TEST_TMP_DIR) + "/family_bad");
    config.termination_distance = distance;
    EXPECT_NE(FamilyTrainer::Create(config).status().message().find("--family_termination_distance"),
              std::string::npos)
        << distance;
  }
}

}  // namespace
}  // namespace modskill::learner::family
