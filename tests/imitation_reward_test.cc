// The imitation reward restricted to some parts' bodies (ImitationRewardConfig::bodies,
// SessionConfig.reward_parts): a body outside them moves the errors but not the reward; a body
// inside them moves both; with none named every body counts, as in PHC. With relative_to_root the
// terms compare the bodies in the root's frame.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/env/env_spec.h"
#include "server/core/env/imitation_reward.h"
#include "server/core/env/humanoid_state.h"

namespace modskill {
namespace {

constexpr int kBodies = 24;

HumanoidState StandingState() {
  HumanoidState state;
  state.Resize(kBodies, 69);
  for (int b = 0; b < kBodies; ++b) {
    state.body_pos[b] = Vec3(0.1 * b, 0.0, 1.0);
    state.body_rot[b] = Quat::Identity();
    state.body_vel[b] = Vec3::Zero();
    state.body_ang_vel[b] = Vec3::Zero();
  }
  return state;
}

double Reward(const float* terms) { return terms[kRewardPos] + terms[kRewardRot] + terms[kRewardVel] + terms[kRewardAngVel]; }

TEST(ImitationRewardTest, OnlyTheNamedBodiesAreRewarded) {
  const HumanoidState reference = StandingState();
  ImitationRewardConfig arms;
  arms.bodies = {16, 18, 20, 22};  // one arm's bodies
  ImitationRewardConfig every_body;

  // A leg body 0.2 m off: every-body reward and the errors see it, the arm's reward does not.
  HumanoidState leg_off = reference;
  leg_off.body_pos[2] += Vec3(0.2, 0, 0);
  float terms[kNumRewardTerms] = {};
  const TrackingErrors errors = ComputeImitationTerms(arms, leg_off, reference, terms);
  EXPECT_NEAR(Reward(terms), 1.0, 1e-6);
  EXPECT_NEAR(errors.max_body_distance, 0.2, 1e-9);
  EXPECT_NEAR(errors.mean_body_distance, 0.2 / kBodies, 1e-9);
  ComputeImitationTerms(every_body, leg_off, reference, terms);
  EXPECT_NEAR(terms[kRewardPos], 0.5 * std::exp(-100 * 0.04 / (3.0 * kBodies)), 1e-6);

  // The same offset on an arm body costs the arm's reward more than the whole body's: it is
  // averaged over 4 bodies instead of 24.
  HumanoidState arm_off = reference;
  arm_off.body_pos[18] += Vec3(0.2, 0, 0);
  ComputeImitationTerms(arms, arm_off, reference, terms);
  EXPECT_NEAR(terms[kRewardPos], 0.5 * std::exp(-100 * 0.04 / (3.0 * 4)), 1e-6);
  float whole[kNumRewardTerms] = {};
  ComputeImitationTerms(every_body, arm_off, reference, whole);
  EXPECT_LT(terms[kRewardPos], whole[kRewardPos]);
  EXPECT_NEAR(terms[kRewardRot] + terms[kRewardVel] + terms[kRewardAngVel], 0.5, 1e-6);
}

// The whole body moved rigidly (the root's drift: shifted, turned, sliding): relative to the
// root every body is where the reference has it, so reward_relative_to_root pays in full while
// the world-frame reward and the errors see the drift. An arm off in the root's frame costs
// the same either way.
TEST(ImitationRewardTest, RelativeToRootIgnoresTheRootsDrift) {
  const HumanoidState reference = StandingState();
  ImitationRewardConfig arms_relative;
  arms_relative.bodies = {16, 18, 20, 22};
  arms_relative.relative_to_root = true;
  ImitationRewardConfig arms_world;
  arms_world.bodies = arms_relative.bodies;

  const Quat turn(Eigen::AngleAxisd(0.4, Vec3::UnitZ()));
  const Vec3 shift(0.3, -0.2, 0.05), slide(0.5, 0.0, 0.0);
  HumanoidState drifted = reference;
  for (int b = 0; b < kBodies; ++b) {
    drifted.body_pos[b] = turn * reference.body_pos[b] + shift;
    drifted.body_rot[b] = turn * reference.body_rot[b];
    drifted.body_vel[b] = turn * reference.body_vel[b] + slide;
  }
  float terms[kNumRewardTerms] = {};
  const TrackingErrors errors = ComputeImitationTerms(arms_relative, drifted, reference, terms);
  EXPECT_NEAR(Reward(terms), 1.0, 1e-6);
  EXPECT_GT(errors.mean_body_distance, 0.2);
  ComputeImitationTerms(arms_world, drifted, reference, terms);
  EXPECT_LT(Reward(terms), 0.9);

  HumanoidState arm_off = reference;
  arm_off.body_pos[18] += Vec3(0.2, 0, 0);
  float world[kNumRewardTerms] = {};
  ComputeImitationTerms(arms_relative, arm_off, reference, terms);
  ComputeImitationTerms(arms_world, arm_off, reference, world);
  EXPECT_NEAR(terms[kRewardPos], 0.5 * std::exp(-100 * 0.04 / (3.0 * 4)), 1e-6);
  EXPECT_NEAR(terms[kRewardPos], world[kRewardPos], 1e-6);
}

}  // namespace
}  // namespace modskill
