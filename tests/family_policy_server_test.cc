// A motor-skill family's exported policy.pt end to end: the family trainer writes it; it holds the
// policy, P(a) and the elites; the server rolls it out at task parameters a given by name (and
// refuses values outside the trained range, unknown names, other clips, and family parameters for
// a tracker); QueryFamily returns the trained ranges, P(a) and the nearest elites; a task policy
// cannot take it as its skills; an upgrade gives a file without a physics record its session's.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/family_elites.h"
#include "common/policy/physics_settings.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/physics_wire.h"
#include "common/wire/tensor_codec.h"
#include "learner/family/family_session.h"
#include "learner/family/family_trainer.h"
#include "learner/policy_import.h"
#include "learner/policy_upgrade.h"
#include "tests/family_test_config.h"
#include "tests/server_fixture.h"

namespace modskill::learner::family {
namespace {

using ::testing::HasSubstr;

// One family run shared by the tests: two iterations on the walk over gravity 4-14.
class FamilyPolicyTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    server_ = StartTestServer().release();
    ASSERT_NE(server_, nullptr);
    // ctest runs each test of the suite as its own process, side by side: a directory each.
    run_dir_ = new std::string(absl::StrCat(MODSKILL_TEST_TMP_DIR, "/family_policy_", getpid()));
    std::filesystem::remove_all(*run_dir_);
    FamilyTrainerConfig config = SmallFamilyConfig(server_->port(), *run_dir_);
    config.max_iterations = 2;
    auto trainer = FamilyTrainer::Create(config);
    ASSERT_TRUE(trainer.ok()) << trainer.status();
    HurryThroughTheClip(**trainer);
    ASSERT_TRUE((*trainer)->Run([] { return false; }).ok());
    trainer_ = trainer->release();
  }
  static void TearDownTestSuite() {
    delete trainer_;
    delete server_;
    if (run_dir_ != nullptr) std::filesystem::remove_all(*run_dir_);
    delete run_dir_;
  }
  // A failed suite set-up fails every test (gtest would report them skipped).
  void SetUp() override { ASSERT_NE(trainer_, nullptr) << "the family run of SetUpTestSuite failed"; }

  static std::string PolicyBytes() {
    auto bytes = ReadFileToString(*run_dir_ + "/policy.pt", size_t{1} << 30);
    EXPECT_TRUE(bytes.ok()) << bytes.status();
    return bytes.ok() ? *bytes : "";
  }

  static v1::RolloutRequest FamilyRollout(std::vector<std::pair<std::string, double>> params) {
    v1::RolloutRequest request;
    request.set_checkpoint_bytes(PolicyBytes());
    for (const auto& [name, value] : params) (*request.mutable_family_params())[name] = value;
    return request;
  }

  static RunningServer* server_;
  static FamilyTrainer* trainer_;
  static std::string* run_dir_;
};

RunningServer* FamilyPolicyTest::server_ = nullptr;
FamilyTrainer* FamilyPolicyTest::trainer_ = nullptr;
std::string* FamilyPolicyTest::run_dir_ = nullptr;

TEST_F(FamilyPolicyTest, PolicyFileHoldsThePolicyTheParameterizationAndTheElites) {
  auto checkpoint = PolicyCheckpoint::LoadFile(*run_dir_ + "/policy.pt");
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  const PolicySpec& spec = (*checkpoint)->spec();
  ASSERT_TRUE(spec.is_family());
  EXPECT_EQ(spec.family_clip, "deepmimic_walk");
  EXPECT_EQ(spec.family_frames, 38);
  ASSERT_EQ(spec.family.size(), 1u);
  EXPECT_EQ(spec.family[0].name, "gravity");
  EXPECT_EQ(spec.family[0].hi, 14);
  EXPECT_EQ(spec.action.mode, ActionMode::kResidual);
  ASSERT_GT(trainer_->elites().size(), 0);
  EXPECT_EQ(static_cast<int64_t>((*checkpoint)->family_elites().size()), trainer_->elites().size());
  for (const FamilyEliteRecord& elite : (*checkpoint)->family_elites()) {
    ASSERT_EQ(elite.params.size(), 1u);
    EXPECT_GE(elite.params[0], 4.0);  // in m/s^2, not normalized
    EXPECT_LE(elite.params[0], 14.0);
  }

  // forward(obs) is the trainer's mean action, normalization included.
  torch::manual_seed(3);
  const torch::Tensor obs = 2 * torch::randn({5, spec.obs_size});
  std::vector<float> actions(5 * spec.action_size);
  ASSERT_TRUE((*checkpoint)->Act(obs.data_ptr<float>(), 5, actions.data()).ok());
  const torch::Tensor expected = trainer_->model()->Mean(obs).detach();
  EXPECT_TRUE(torch::allclose(torch::from_blob(actions.data(), {5, spec.action_size}), expected, 1e-4, 1e-5));

  // parameterization(a, phase) is the trainer's P(a) over the clip's frames.
  ASSERT_TRUE((*checkpoint)->has_parameterization());
  auto trajectory = (*checkpoint)->Parameterization({0.3});
  ASSERT_TRUE(trajectory.ok()) << trajectory.status();
  auto reference = trainer_->parameterization()->Trajectory({0.3}, 38);
  ASSERT_TRUE(reference.ok());
  EXPECT_TRUE(torch::allclose(torch::from_blob(trajectory->data(), {38, spec.action_size}), reference->detach(), 1e-4, 1e-5));
  EXPECT_FALSE((*checkpoint)->Parameterization({0.3, 0.5}).ok());
}

TEST_F(FamilyPolicyTest, RolloutRunsTheFamilyAtTheGivenParameters) {
  auto client = ConnectTo(*server_);
  ASSERT_NE(client, nullptr);
  std::vector<v1::ClipMetrics> runs;
  for (double gravity : {4.0, 14.0}) {
    int frames = 0;
    auto metrics = client->Rollout(FamilyRollout({{"gravity", gravity}}), nullptr);
    v1::RolloutRequest streamed = FamilyRollout({{"gravity", gravity}});
    streamed.set_stream_frames(true);
    auto again = client->Rollout(streamed, [&](const v1::RolloutFrame& frame) {
      ++frames;
      EXPECT_EQ(frame.clip(), "deepmimic_walk");
    });
    ASSERT_TRUE(metrics.ok()) << metrics.status();
    ASSERT_TRUE(again.ok()) << again.status();
    ASSERT_EQ(metrics->size(), 1u);
    const v1::ClipMetrics& m = (*metrics)[0];
    EXPECT_EQ(m.clip(), "deepmimic_walk");
    ASSERT_TRUE(m.has_family());
    EXPECT_EQ(m.family().params().at("gravity"), gravity);
    EXPECT_GE(m.family().fitness(), 0.0);
    EXPECT_LE(m.family().fitness(), 1.2);
    EXPECT_GT(m.family().apex_height_m(), 0.5);  // the pelvis starts at about 0.9 m
    EXPECT_GT(m.family().highest_effector_m(), 0.3);
    EXPECT_GT(m.family().final_phase(), 0.0);
    EXPECT_EQ(m.family().reached_end(), m.family().final_phase() >= 37);
    EXPECT_EQ(frames, m.steps() + 1);  // the start state and one frame per step
    // The same policy and parameters: the same episode.
    EXPECT_EQ((*again)[0].family().final_phase(), m.family().final_phase());
    runs.push_back(m);
  }
  // Gravity reaches the physics: the two episodes differ.
  EXPECT_NE(runs[0].g_mpjpe_mm(), runs[1].g_mpjpe_mm());

  // Left out: the middle of the trained range.
  auto middle = client->Rollout(FamilyRollout({}), nullptr);
  ASSERT_TRUE(middle.ok()) << middle.status();
  EXPECT_EQ((*middle)[0].family().params().at("gravity"), 9.0);
}

TEST_F(FamilyPolicyTest, BadFamilyRequestsAreNamed) {
  auto client = ConnectTo(*server_);
  ASSERT_NE(client, nullptr);
  auto outside = client->Rollout(FamilyRollout({{"gravity", 20}}), nullptr);
  EXPECT_EQ(outside.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(outside.status().message().find("family_params[gravity]"), std::string::npos) << outside.status();
  EXPECT_NE(outside.status().message().find("[4, 14]"), std::string::npos) << outside.status();
  auto nan = client->Rollout(FamilyRollout({{"gravity", std::nan("")}}), nullptr);
  EXPECT_EQ(nan.status().code(), absl::StatusCode::kInvalidArgument);
  auto unknown = client->Rollout(FamilyRollout({{"leg_length", 1.0}}), nullptr);
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(unknown.status().message().find("leg_length"), std::string::npos) << unknown.status();
  v1::RolloutRequest other_clip = FamilyRollout({});
  other_clip.add_clips("deepmimic_jump");
  auto refused_clip = client->Rollout(other_clip, nullptr);
  EXPECT_EQ(refused_clip.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(refused_clip.status().message().find("deepmimic_walk"), std::string::npos) << refused_clip.status();
  v1::RolloutRequest skills = FamilyRollout({});
  skills.set_record_skills(true);
  skills.set_stream_frames(true);
  EXPECT_EQ(client->Rollout(skills, nullptr).status().code(), absl::StatusCode::kFailedPrecondition);

  // A tracker given family parameters.
  auto env = client->Describe();
  ASSERT_TRUE(env.ok());
  PolicySpec tracker;
  tracker.part_layout = env->part_layout();
  tracker.obs_size = env->obs_size();
  tracker.action_size = env->action_size();
  tracker.joint_names.assign(env->joint_names().begin(), env->joint_names().end());
  tracker.control_dt = env->control_dt();
  auto tracker_bytes = AffinePolicyBytes(tracker, {}, {});
  ASSERT_TRUE(tracker_bytes.ok());
  v1::RolloutRequest tracking;
  tracking.set_checkpoint_bytes(*tracker_bytes);
  tracking.add_clips("deepmimic_walk");
  (*tracking.mutable_family_params())["gravity"] = 5;
  auto not_family = client->Rollout(tracking, nullptr);
  EXPECT_EQ(not_family.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(not_family.status().message().find("family_params"), std::string::npos) << not_family.status();

  // QueryFamily on a tracker, and too many elites asked for.
  v1::QueryFamilyRequest query;
  query.set_checkpoint_bytes(*tracker_bytes);
  EXPECT_EQ(client->QueryFamily(query).status().code(), absl::StatusCode::kFailedPrecondition);
  query.set_checkpoint_bytes(PolicyBytes());
  query.set_nearest_elites(65);
  auto too_many = client->QueryFamily(query);
  EXPECT_EQ(too_many.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(too_many.status().message().find("nearest_elites"), std::string::npos) << too_many.status();

  // A task policy cannot take a family's policy as its skills.
  auto as_skills = ReadExportedPolicy(*run_dir_ + "/policy.pt");
  EXPECT_EQ(as_skills.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(as_skills.status().message().find("family"), std::string::npos) << as_skills.status();
}

TEST_F(FamilyPolicyTest, QueryFamilyGivesParameterizationAndNearestElites) {
  auto client = ConnectTo(*server_);
  ASSERT_NE(client, nullptr);
  v1::QueryFamilyRequest query;
  query.set_checkpoint_bytes(PolicyBytes());
  (*query.mutable_params())["gravity"] = 7;
  auto answer = client->QueryFamily(query);
  ASSERT_TRUE(answer.ok()) << answer.status();
  EXPECT_EQ(answer->clip(), "deepmimic_walk");
  ASSERT_EQ(answer->ranges_size(), 1);
  EXPECT_EQ(answer->ranges(0).lo(), 4);
  EXPECT_EQ(answer->params().at("gravity"), 7);
  ASSERT_EQ(answer->normalized_params_size(), 1);
  EXPECT_NEAR(answer->normalized_params(0), 0.3, 1e-12);
  EXPECT_EQ(answer->elites(), trainer_->elites().size());
  ASSERT_EQ(answer->parameterization_columns_size(), 70);
  EXPECT_EQ(answer->parameterization_columns(69), "tau");
  std::vector<float> trajectory;
  ASSERT_TRUE(ReadFloatTensor(answer->parameterization(), "parameterization", &trajectory).ok());
  ASSERT_EQ(trajectory.size(), 38u * 70u);
  auto reference = trainer_->parameterization()->Trajectory({0.3}, 38);
  ASSERT_TRUE(reference.ok());
  EXPECT_TRUE(torch::allclose(torch::from_blob(trajectory.data(), {38, 70}), reference->detach(), 1e-4, 1e-5));
  // The nearest elites, nearest first, at most the paper's k = 5.
  ASSERT_GT(answer->nearest_elites_size(), 0);
  EXPECT_LE(answer->nearest_elites_size(), 5);
  for (int k = 0; k < answer->nearest_elites_size(); ++k) {
    const v1::FamilyElite& elite = answer->nearest_elites(k);
    EXPECT_NEAR(elite.distance(), std::abs(elite.params().at("gravity") - 7.0) / 10.0, 1e-9);
    if (k > 0) EXPECT_GE(elite.distance(), answer->nearest_elites(k - 1).distance());
  }
}

// A family file from before policies recorded their physics (the shipped family_jump_gravity)
// gains its family session's physics, stable PD at the server's rate, with forward, P(a) and the
// elites unchanged. Other recorded physics is refused by name, and a server's own Describe, whose
// servos a family session does not use, is no source for it.
TEST_F(FamilyPolicyTest, AnUpgradeRecordsTheFamilySessionsPhysics) {
  const std::string trained = *run_dir_ + "/policy.pt";
  auto original = PolicyCheckpoint::LoadFile(trained);
  ASSERT_TRUE(original.ok()) << original.status();
  const PolicySpec spec = (*original)->spec();
  ASSERT_TRUE(spec.physics.recorded());
  EXPECT_EQ(spec.physics.pd_mode, kPdModeStablePd);

  // The same file without the record, as the family trainer wrote it before 2026-12-07.
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}, {kCheckpointFamilyElitesFile, ""}};
  torch::jit::Module module = torch::jit::load(trained, torch::kCPU, extra);
  PolicySpec unrecorded = spec;
  unrecorded.physics = PhysicsSettings{};
  extra[kCheckpointSpecFile] = unrecorded.ToJson();
  const std::string old_file = *run_dir_ + "/unrecorded.pt", upgraded = *run_dir_ + "/upgraded.pt";
  module.save(old_file, extra);
  ASSERT_FALSE((*PolicyCheckpoint::LoadFile(old_file))->spec().physics.recorded());

  auto client = ConnectTo(*server_);
  ASSERT_NE(client, nullptr);
  auto session = DescribeFamilySession(*client, unrecorded);
  ASSERT_TRUE(session.ok()) << session.status();
  auto upgrade = UpgradeFamilyPolicy(old_file, *session, upgraded);
  ASSERT_TRUE(upgrade.ok()) << upgrade.status();
  EXPECT_TRUE(upgrade->physics_added);
  EXPECT_EQ(upgrade->forward_difference, 0.0);
  EXPECT_FALSE(std::filesystem::exists(upgraded + ".upgrade"));
  auto stamped = PolicyCheckpoint::LoadFile(upgraded);
  ASSERT_TRUE(stamped.ok()) << stamped.status();
  EXPECT_EQ((*stamped)->spec().physics.ToJson(), spec.physics.ToJson());
  EXPECT_EQ((*stamped)->spec().ToJson(), spec.ToJson());
  ASSERT_EQ((*stamped)->family_elites().size(), (*original)->family_elites().size());
  for (size_t i = 0; i < (*stamped)->family_elites().size(); ++i) {
    EXPECT_EQ((*stamped)->family_elites()[i].params, (*original)->family_elites()[i].params);
    EXPECT_EQ((*stamped)->family_elites()[i].fitness, (*original)->family_elites()[i].fitness);
  }
  auto before = (*original)->Parameterization({0.3}), after = (*stamped)->Parameterization({0.3});
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_EQ(*before, *after);

  // A file that records other servos than its family session's is refused, and nothing written.
  v1::EnvSpec other = *session;
  other.mutable_physics()->set_pd_gain_scale(2);
  const std::string refused = *run_dir_ + "/refused.pt";
  auto mismatch = UpgradeFamilyPolicy(trained, other, refused);
  EXPECT_EQ(mismatch.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(mismatch.status().message()), HasSubstr("pd_gain_scale 1 against this server's 2"));
  EXPECT_FALSE(std::filesystem::exists(refused));

  auto described = client->Describe("5part");
  ASSERT_TRUE(described.ok()) << described.status();
  auto not_a_session = UpgradeFamilyPolicy(old_file, *described, refused);
  EXPECT_EQ(not_a_session.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(refused));
  EXPECT_EQ(DescribeFamilySession(*client, PolicySpec{}).status().code(), absl::StatusCode::kInvalidArgument);
}

// The shipped family (data/policies/family_jump_gravity) records the physics its family session
// simulates in (stable PD at 120 Hz), so a server whose family sessions differ refuses it by name.
TEST_F(FamilyPolicyTest, TheShippedFamilyRecordsItsSessionsPhysics) {
  auto shipped = PolicyCheckpoint::LoadFile(std::string(MODSKILL_REPO_DIR) + "/data/policies/family_jump_gravity/policy.pt");
  ASSERT_TRUE(shipped.ok()) << shipped.status();
  const PhysicsSettings& physics = (*shipped)->spec().physics;
  ASSERT_TRUE(physics.recorded());
  EXPECT_EQ(physics.pd_mode, kPdModeStablePd);
  EXPECT_NEAR(physics.physics_dt, 1.0 / 120, 1e-12);
  auto client = ConnectTo(*server_);
  ASSERT_NE(client, nullptr);
  auto session = DescribeFamilySession(*client, (*shipped)->spec());
  ASSERT_TRUE(session.ok()) << session.status();
  EXPECT_EQ(PhysicsDifference(physics, PhysicsOf(*session), "the family session's"), "");
}

}  // namespace
}  // namespace modskill::learner::family
