// The gRPC server end to end, rollouts: TorchScript checkpoints by path and by bytes, bad
// checkpoints, the action mode a policy was trained in, old policy specs.

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "server/core/env/policy_fit.h"
#include "tests/server_fixture.h"
#include "tests/simulation_server_fixture.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

std::string ZeroPolicy(const std::string& layout_name = "5part") {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  const EnvSpec spec = MakeEnvSpec(**humanoid, *catalog->Get(layout_name));
  const std::string path = TempDir() + "/zero_" + layout_name + ".pt";
  EXPECT_TRUE(SaveAffinePolicy(path, PolicySpecForEnv(spec), {}, {}).ok());
  return path;
}

TEST_F(SimulationServerTest, RolloutRunsATorchScriptCheckpoint) {
  v1::RolloutRequest request;
  request.set_checkpoint_path(ZeroPolicy());
  request.add_clips("deepmimic_walk");
  request.add_clips("cmu_02_01");
  request.set_stream_frames(true);
  int frames = 0;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) {
    ++frames;
    EXPECT_EQ(frame.sim_body_pos().shape(0), 24);
    EXPECT_EQ(frame.ref_body_pos().data().size(), 24u * 3 * 4);
  });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_EQ(metrics->size(), 2u);
  int steps = 0;
  for (const v1::ClipMetrics& clip : *metrics) {
    steps += clip.steps() + 1;
    EXPECT_GT(clip.g_mpjpe_mm(), 0);
    EXPECT_GE(clip.g_mpjpe_mm(), 0.5 * clip.mpjpe_mm());
    EXPECT_EQ(clip.body_error_mm_size(), 24);
    EXPECT_EQ(clip.part_error_mm_size(), 5);
    EXPECT_GT(clip.max_mean_body_error_m(), 0.0);
    // Evaluation termination: a failed clip went past 0.5 m mean error, a successful one never did.
    EXPECT_EQ(clip.success(), clip.max_mean_body_error_m() <= 0.5);
  }
  EXPECT_EQ(frames, steps);
  // The zero policy holds joints at their range midpoints: it falls, so it fails.
  EXPECT_FALSE((*metrics)[0].success());
  // The same checkpoint as bytes.
  v1::RolloutRequest by_bytes;
  by_bytes.set_checkpoint_bytes(*ReadFileToString(ZeroPolicy(), 1 << 30));
  by_bytes.add_clips("deepmimic_walk");
  auto again = client_->Rollout(by_bytes);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ((*again)[0].steps(), (*metrics)[0].steps());
  EXPECT_DOUBLE_EQ((*again)[0].g_mpjpe_mm(), (*metrics)[0].g_mpjpe_mm());
}

TEST_F(SimulationServerTest, RolloutBadInputs) {
  auto expect = [&](const v1::RolloutRequest& request, absl::StatusCode code, const std::string& needle) {
    auto result = client_->Rollout(request);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), code) << result.status();
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  };
  v1::RolloutRequest request;
  expect(request, absl::StatusCode::kInvalidArgument, "checkpoint");
  request.set_checkpoint_path(TempDir() + "/missing.pt");
  expect(request, absl::StatusCode::kNotFound, "checkpoint_path");
  const std::string garbage = TempDir() + "/garbage.pt";
  ASSERT_TRUE(WriteFileAtomically(garbage, "this is not a zip archive").ok());
  request.set_checkpoint_path(garbage);
  expect(request, absl::StatusCode::kInvalidArgument, "TorchScript");
  request.set_checkpoint_bytes(std::string(1000, 'x'));
  expect(request, absl::StatusCode::kInvalidArgument, "TorchScript");
  request.set_checkpoint_path(ZeroPolicy("3part"));  // trained with another layout: fine, the server offers it
  request.add_clips("deepmimic_walk");
  EXPECT_TRUE(client_->Rollout(request).ok());
  // A checkpoint for another observation size.
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  PolicySpec other = PolicySpecForEnv(MakeEnvSpec(**humanoid, *catalog->Get("5part")));
  other.obs_size = 100;
  const std::string mismatched = TempDir() + "/mismatched.pt";
  ASSERT_TRUE(SaveAffinePolicy(mismatched, other, {}, {}).ok());
  request.set_checkpoint_path(mismatched);
  expect(request, absl::StatusCode::kFailedPrecondition, "obs_size");
  request.set_checkpoint_path(ZeroPolicy());
  request.add_clips("not_a_clip");
  expect(request, absl::StatusCode::kNotFound, "clips[1]");
  // A checkpoint runs in the action mode it was trained in; insisting on another is refused.
  request.clear_clips();
  request.add_clips("deepmimic_walk");
  request.set_action_mode(v1::RESIDUAL);
  expect(request, absl::StatusCode::kFailedPrecondition, "action_mode");
  request.set_action_mode(static_cast<v1::ActionMode>(12));
  expect(request, absl::StatusCode::kInvalidArgument, "action_mode");
  request.set_action_mode(v1::ABSOLUTE);
  EXPECT_TRUE(client_->Rollout(request).ok());
}

// The zero residual policy is open-loop reference tracking: it runs in residual mode (recorded in
// the checkpoint) and tracks the pose far better than the zero absolute policy, which holds every
// joint at its range midpoint.
TEST_F(SimulationServerTest, RolloutRunsAPolicyInItsTrainedActionMode) {
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(OpenLoopPolicyBytes());
  request.add_clips("deepmimic_walk");
  auto open_loop = client_->Rollout(request);
  ASSERT_TRUE(open_loop.ok()) << open_loop.status();
  request.set_action_mode(v1::ABSOLUTE);
  auto refused = client_->Rollout(request);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("residual"));
  v1::RolloutRequest absolute;
  absolute.set_checkpoint_path(ZeroPolicy());
  absolute.add_clips("deepmimic_walk");
  auto falls = client_->Rollout(absolute);
  ASSERT_TRUE(falls.ok()) << falls.status();
  // (Under evaluation termination the collapse takes a second either way; the pose error tells.)
  EXPECT_LT((*open_loop)[0].mpjpe_mm(), 0.75 * (*falls)[0].mpjpe_mm());
}

// A policy runs only under the physics it was trained in: one trained at 60 Hz, or with other
// servos, is refused by a default server, naming the setting and the flag; one from before the
// field (no physics recorded) still runs.
TEST_F(SimulationServerTest, RolloutRefusesAPolicyTrainedUnderOtherPhysics) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  ASSERT_TRUE(catalog.ok());
  PhysicsOptions slow;
  slow.substeps = 2;
  PhysicsOptions soft;
  soft.pd_gain_scale = 0.5;
  const std::pair<PhysicsOptions, const char*> others[] = {
      {slow, "checkpoint: trained with physics_dt 0.0166667 s (60 Hz) against this server's 0.00833333 s (120 Hz); "
             "the server's --substeps sets it"},
      {soft, "checkpoint: trained with pd_gain_scale 0.5 against this server's 1; the server's --pd_gain_scale sets it"}};
  for (const auto& [physics, message] : others) {
    auto humanoid = HumanoidModel::Create(DefaultSpec(), physics);
    ASSERT_TRUE(humanoid.ok());
    PolicySpec trained = PolicySpecForEnv(MakeEnvSpec(**humanoid, *catalog->Get("5part")));
    auto bytes = AffinePolicyBytes(trained, {}, {});
    ASSERT_TRUE(bytes.ok());
    v1::RolloutRequest request;
    request.set_checkpoint_bytes(*bytes);
    request.add_clips("deepmimic_walk");
    auto refused = client_->Rollout(request);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_THAT(std::string(refused.status().message()), HasSubstr(message));

    trained.physics = PhysicsSettings();  // as written before the field
    request.set_checkpoint_bytes(*AffinePolicyBytes(trained, {}, {}));
    EXPECT_TRUE(client_->Rollout(request).ok());
  }
}

// Checkpoints from before action modes carry no action_mode: they were trained in absolute mode.
TEST(PolicySpecTest, OldSpecsLoadAsAbsoluteAndBadModesAreRefused) {
  const std::string old_json =
      R"({"part_layout": "5part", "obs_size": 934, "action_size": 69, "joint_names": [], "control_dt": 0.0333})";
  auto old_spec = PolicySpec::FromJson(old_json);
  ASSERT_TRUE(old_spec.ok()) << old_spec.status();
  EXPECT_EQ(old_spec->action.mode, ActionMode::kAbsolute);
  PolicySpec residual = *old_spec;
  residual.action = ActionMapping{ActionMode::kResidual, 0.25};
  auto round_trip = PolicySpec::FromJson(residual.ToJson());
  ASSERT_TRUE(round_trip.ok());
  EXPECT_EQ(round_trip->action.mode, ActionMode::kResidual);
  EXPECT_DOUBLE_EQ(round_trip->action.residual_scale, 0.25);
  std::string bad = residual.ToJson();
  bad.replace(bad.find("residual\""), 9, "sideways\"");
  auto refused = PolicySpec::FromJson(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("action_mode"));
  // Sizes are checked as written: 2^40 is reported as such, not as 0 after a cast.
  std::string huge = old_json;
  huge.replace(huge.find("934"), 3, "1099511627776");
  auto too_big = PolicySpec::FromJson(huge);
  ASSERT_FALSE(too_big.ok());
  EXPECT_THAT(std::string(too_big.status().message()), HasSubstr("obs_size: 1099511627776"));
  std::string fractional = old_json;
  fractional.replace(fractional.find("69"), 2, "69.5");
  EXPECT_FALSE(PolicySpec::FromJson(fractional).ok());
}

}  // namespace
}  // namespace modskill
