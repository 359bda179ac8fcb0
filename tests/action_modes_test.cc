// Action modes (absolute and residual PD targets) and the training termination rules: no
// termination on the first step, the no_feet body set, and a distance changed between steps.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "server/core/env/action_mapping.h"
#include "server/core/env/episode_end.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

EnvBatchConfig OneEnv(ActionMode mode) {
  EnvBatchConfig config;
  config.num_envs = 1;
  config.seed = 5;
  config.env.action.mode = mode;
  return config;
}

// Steps env 0 from `frame` of `clip` with zero actions until its episode ends; the steps taken.
int StepsUntilDone(EnvBatch& batch, const std::string& clip, int frame, int limit = 200) {
  batch.env(0).ResetTo(batch.motions().Find(clip), frame, batch.row(0));
  const std::vector<float> zeros(batch.spec().action_size, 0.f);
  for (int s = 1; s <= limit; ++s) {
    EXPECT_TRUE(batch.Step(zeros).ok());
    if (batch.buffers().done[0]) return s;
  }
  return limit;
}

TEST(ActionMappingTest, ResidualZeroIsTheReferencePoseClampedToTheRange) {
  auto batch = MakeBatch(OneEnv(ActionMode::kResidual));
  ASSERT_NE(batch, nullptr);
  const HumanoidModel& humanoid = batch->humanoid();
  const EnvSpec& spec = batch->spec();
  const MotionClip& clip = batch->motions().clip(batch->motions().Find("deepmimic_walk"));
  const double* reference = &clip.dof_pos[static_cast<size_t>(7) * clip.num_hinges()];
  std::vector<float> action(spec.action_size, 0.f);
  std::vector<double> targets(humanoid.num_hinges(), std::nan(""));
  ActionMapping residual{ActionMode::kResidual, 0.5};
  MapActionToPdTargets(residual, humanoid, spec, action.data(), reference, nullptr, targets.data());
  for (int h = 0; h < humanoid.num_hinges(); ++h) {
    const BodySpec& body = humanoid.spec().body(1 + h / 3);
    EXPECT_DOUBLE_EQ(targets[h], std::clamp(reference[h], body.range_low[h % 3], body.range_high[h % 3])) << h;
  }
  // A full action moves each target by residual_scale x the hinge's action scale (inside the range).
  std::fill(action.begin(), action.end(), 0.2f);
  MapActionToPdTargets(residual, humanoid, spec, action.data(), reference, nullptr, targets.data());
  int inside = 0;
  for (int a = 0; a < spec.action_size; ++a) {
    const int h = spec.action_hinge[a];
    const BodySpec& body = humanoid.spec().body(1 + h / 3);
    const double expected = reference[h] + 0.5 * humanoid.action_scale()[h] * 0.2;
    if (expected > body.range_low[h % 3] && expected < body.range_high[h % 3]) {
      EXPECT_NEAR(targets[h], expected, 1e-6) << h;
      ++inside;
    }
  }
  EXPECT_GT(inside, 50);
  // Unclamped (a motor-skill family's mapping), a full action pushes past the range's ends.
  std::fill(action.begin(), action.end(), 1.0f);
  ActionMapping unclamped = residual;
  unclamped.clamp_to_joint_range = false;
  MapActionToPdTargets(unclamped, humanoid, spec, action.data(), reference, nullptr, targets.data());
  int beyond = 0;
  for (int a = 0; a < spec.action_size; ++a) {
    const int h = spec.action_hinge[a];
    EXPECT_NEAR(targets[h], reference[h] + 0.5 * humanoid.action_scale()[h], 1e-6) << h;
    beyond += targets[h] > humanoid.spec().body(1 + h / 3).range_high[h % 3];
  }
  EXPECT_GT(beyond, 0);
  // Absolute mode ignores the reference: offset + scale * a.
  std::fill(action.begin(), action.end(), 0.2f);
  MapActionToPdTargets(ActionMapping{}, humanoid, spec, action.data(), reference, nullptr, targets.data());
  for (int a = 0; a < spec.action_size; ++a) {
    const int h = spec.action_hinge[a];
    EXPECT_NEAR(targets[h], humanoid.action_offset()[h] + humanoid.action_scale()[h] * 0.2, 1e-6);
  }
}

TEST(ActionMappingTest, DampingToTheReferenceRateLeadsResidualTargetsByKdOverKpTimesTheRate) {
  EnvBatchConfig config = OneEnv(ActionMode::kResidual);
  config.physics.damp_to_reference_rate = true;
  auto batch = MakeBatch(config);
  ASSERT_NE(batch, nullptr);
  const HumanoidModel& humanoid = batch->humanoid();
  const MotionClip& clip = batch->motions().clip(batch->motions().Find("deepmimic_walk"));
  const size_t frame = static_cast<size_t>(7) * clip.num_hinges();
  const double* reference = &clip.dof_pos[frame];
  const double* rate = &clip.dof_vel[frame];
  const std::vector<float> zeros(batch->spec().action_size, 0.f);
  std::vector<double> targets(humanoid.num_hinges(), std::nan(""));
  const ActionMapping residual{ActionMode::kResidual, 0.5};
  MapActionToPdTargets(residual, humanoid, batch->spec(), zeros.data(), reference, rate, targets.data());
  int led = 0;
  for (int h = 0; h < humanoid.num_hinges(); ++h) {
    const BodySpec& body = humanoid.spec().body(1 + h / 3);
    const double lead = humanoid.kd()[h] / humanoid.kp()[h] * rate[h];
    EXPECT_DOUBLE_EQ(targets[h], std::clamp(reference[h] + lead, body.range_low[h % 3], body.range_high[h % 3])) << h;
    led += std::abs(lead) > 1e-3 && std::abs(targets[h] - reference[h]) > 1e-3;
  }
  EXPECT_GT(led, 10);  // a walk moves many hinges at frame 7
  // Absolute targets ignore the reference and its rate.
  MapActionToPdTargets(ActionMapping{}, humanoid, batch->spec(), zeros.data(), reference, rate, targets.data());
  for (int h : batch->spec().action_hinge) EXPECT_DOUBLE_EQ(targets[h], humanoid.action_offset()[h]) << h;
}

TEST(ActionMappingTest, NamesAndScalesAreValidated) {
  EXPECT_EQ(*ParseActionMode("residual"), ActionMode::kResidual);
  EXPECT_EQ(*ParseActionMode("absolute"), ActionMode::kAbsolute);
  auto unknown = ParseActionMode("relative");
  ASSERT_FALSE(unknown.ok());
  EXPECT_THAT(std::string(unknown.status().message()), HasSubstr("relative"));
  for (double bad : {0.0, -0.5, 10.5, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const absl::Status status = ActionMapping{ActionMode::kResidual, bad}.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(status.message()), HasSubstr("residual_scale")) << bad;
  }
  EXPECT_TRUE((ActionMapping{ActionMode::kResidual, 0.2}.Validate().ok()));
  // A bad scale is refused before any env exists.
  EnvBatchConfig config = OneEnv(ActionMode::kResidual);
  config.env.action.residual_scale = -1;
  auto batch = EnvBatch::Create(config, DefaultMotions());
  ASSERT_FALSE(batch.ok());
  EXPECT_THAT(std::string(batch.status().message()), HasSubstr("residual_scale"));
}

TEST(ActionModesTest, ZeroResidualActionsTrackLikeTheReferenceAndOutlastAbsoluteZeros) {
  auto residual = MakeBatch(OneEnv(ActionMode::kResidual));
  auto absolute = MakeBatch(OneEnv(ActionMode::kAbsolute));
  ASSERT_NE(residual, nullptr);
  ASSERT_NE(absolute, nullptr);
  int residual_steps = 0, absolute_steps = 0;
  for (int frame : {0, 10, 20}) {
    residual_steps += StepsUntilDone(*residual, "deepmimic_walk", frame);
    absolute_steps += StepsUntilDone(*absolute, "deepmimic_walk", frame);
  }
  // Zero absolute actions hold every joint at its range midpoint: the character falls at once.
  EXPECT_GT(residual_steps, absolute_steps + 6);
  // Zero residual actions are open-loop reference tracking: the same first step as driving
  // absolute mode with the reference's own actions.
  auto reference = MakeBatch(OneEnv(ActionMode::kAbsolute));
  const int clip = residual->motions().Find("deepmimic_walk");
  residual->env(0).ResetTo(clip, 4, residual->row(0));
  reference->env(0).ResetTo(clip, 4, reference->row(0));
  ASSERT_TRUE(residual->Step(std::vector<float>(69, 0.f)).ok());
  ASSERT_TRUE(reference->Step(ReferenceActions(*reference)).ok());
  EXPECT_NEAR(residual->buffers().mean_body_error[0], reference->buffers().mean_body_error[0], 2e-3);
}

TEST(TerminationTest, NeverOnTheFirstStepAfterAReset) {
  EnvBatchConfig config = OneEnv(ActionMode::kResidual);
  config.env.termination_distance = 1e-6;  // any error at all ends the episode...
  auto batch = MakeBatch(config);
  ASSERT_NE(batch, nullptr);
  // ...but not on the first step.
  EXPECT_EQ(StepsUntilDone(*batch, "deepmimic_walk", 3), 2);
  EXPECT_EQ(batch->buffers().truncated[0], 0);
  EXPECT_EQ(batch->buffers().end_cause[0], static_cast<uint8_t>(EpisodeEnd::kTracking));
}

TEST(TerminationTest, NoFeetWatchesEveryBodyButAnklesAndToes) {
  EnvBatchConfig config = OneEnv(ActionMode::kResidual);
  auto all = MakeBatch(config);
  config.env.termination_bodies = TerminationBodies::kNoFeet;
  auto no_feet = MakeBatch(config);
  ASSERT_NE(all, nullptr);
  ASSERT_NE(no_feet, nullptr);
  EXPECT_EQ(all->termination_body_ids().size(), 24u);
  ASSERT_EQ(no_feet->termination_body_ids().size(), 20u);
  for (int b : no_feet->termination_body_ids()) {
    const std::string& name = DefaultSpec().body(b).name;
    EXPECT_EQ(name.find("Ankle"), std::string::npos) << name;
    EXPECT_EQ(name.find("Toe"), std::string::npos) << name;
  }
  // Swing only the left foot away: all-body termination ends the episode, no_feet does not.
  for (EnvBatch* batch : {all.get(), no_feet.get()}) {
    const int clip = batch->motions().Find("deepmimic_walk");
    batch->env(0).ResetTo(clip, 5, batch->row(0));
    ASSERT_TRUE(batch->Step(std::vector<float>(69, 0.f)).ok());
    ASSERT_EQ(batch->buffers().done[0], 0);
    // Bend the knee hard (its _x hinge turns about +y): the ankle and toe swing away, the knee
    // itself and everything above it stay.
    const int knee = DefaultSpec().BodyIndex("L_Knee");
    batch->env(0).mutable_data()->qpos[7 + 3 * (knee - 1) + 0] += 1.6;
    batch->env(0).RefreshObservation(batch->row(0));
    ASSERT_TRUE(batch->Step(std::vector<float>(69, 0.f)).ok());
    EXPECT_GT(batch->buffers().max_body_error[0], 0.25f);
  }
  EXPECT_EQ(all->buffers().done[0], 1);
  EXPECT_EQ(no_feet->buffers().done[0], 0);
}

TEST(TerminationTest, DistanceChangesBetweenStepsAndIsValidated) {
  auto batch = MakeBatch(OneEnv(ActionMode::kAbsolute));
  ASSERT_NE(batch, nullptr);
  // Zero absolute actions fall: with 100 m nothing terminates...
  ASSERT_TRUE(batch->SetTerminationDistance(100).ok());
  EXPECT_EQ(StepsUntilDone(*batch, "cmu_02_01", 10, 30), 30);
  // ...with 1 mm the second step does.
  ASSERT_TRUE(batch->SetTerminationDistance(0.001).ok());
  EXPECT_EQ(StepsUntilDone(*batch, "cmu_02_01", 10, 30), 2);
  for (double bad : {0.0, -1.0, 101.0, std::numeric_limits<double>::quiet_NaN()}) {
    const absl::Status status = batch->SetTerminationDistance(bad);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(status.message()), HasSubstr("termination_distance"));
  }
  EXPECT_DOUBLE_EQ(batch->env_config().termination_distance, 0.001);
}

}  // namespace
}  // namespace modskill
