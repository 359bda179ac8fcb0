// Variable time-step GAE (Eq. 9, learner/family/variable_step_gae.h): hand-computed cases, the
// continuous reward's weight, time-outs vs failures, and the constant-step case being ordinary
// GAE (learner/gae.h) exactly.
#include "learner/family/variable_step_gae.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "learner/gae.h"

namespace modskill::learner::family {
namespace {

torch::Tensor D(std::vector<double> v, int64_t t, int64_t n) { return torch::tensor(v, torch::kFloat64).reshape({t, n}); }

VariableStepRollout OneEnv(std::vector<double> r_c, std::vector<double> r_s, std::vector<double> dphi,
                           std::vector<double> values, double last_value) {
  const int64_t t = static_cast<int64_t>(values.size());
  VariableStepRollout r;
  r.continuous_reward = D(r_c, t, 1);
  r.spike_reward = D(r_s, t, 1);
  r.phase_step = D(dphi, t, 1);
  r.values = D(values, t, 1);
  r.terminated = torch::zeros({t, 1}, torch::kFloat64);
  r.last_values = torch::tensor({last_value}, torch::kFloat64);
  return r;
}

TEST(FamilyVariableStepGaeTest, ContinuousWeightIsTheNormalizedIntegral) {
  const double g = 0.95;
  EXPECT_EQ(ContinuousRewardWeight(g, 1.0), 1.0);              // exactly: a unit step weighs r_c by 1
  EXPECT_NEAR(ContinuousRewardWeight(g, 2.0), 1 + g, 1e-12);   // two unit steps: r + gamma r
  // int_0^dphi g^x dx / int_0^1 g^x dx, against the closed form with ln(g)
  for (double dphi : {0.1, 0.37, 1.5, 2.7}) {
    EXPECT_NEAR(ContinuousRewardWeight(g, dphi), ((std::pow(g, dphi) - 1) / std::log(g)) / ((g - 1) / std::log(g)), 1e-12);
    // additive over consecutive steps: w(a + b) = w(a) + g^a w(b)
    EXPECT_NEAR(ContinuousRewardWeight(g, dphi + 0.4), ContinuousRewardWeight(g, dphi) + std::pow(g, dphi) * ContinuousRewardWeight(g, 0.4), 1e-12);
  }
  // a short step earns about dphi times the rate (the integral's slope at 0 is ln g / (g - 1))
  EXPECT_NEAR(ContinuousRewardWeight(g, 1e-6) / 1e-6, std::log(g) / (g - 1), 1e-6);
}

TEST(FamilyVariableStepGaeTest, HandComputedTwoSteps) {
  // gamma 0.9, lambda 0.8; step 0: dphi 2, r_c 1, r_s 0.5, V 2; step 1: dphi 0.5, r_c 2, r_s 0, V 3; V_last 4.
  const double g = 0.9, l = 0.8;
  absl::StatusOr<Advantages> out = ComputeVariableStepGae(OneEnv({1, 2}, {0.5, 0}, {2, 0.5}, {2, 3}, 4), g, l);
  ASSERT_TRUE(out.ok()) << out.status();
  const double w1 = (std::pow(g, 0.5) - 1) / (g - 1);              // 0.4868...
  const double delta1 = w1 * 2 + std::pow(g, 0.5) * 4 - 3;         // 1.7683...
  const double delta0 = (1 + g) * 1 + 0.5 + g * g * 3 - 2;         // w(2) = 1 + g: 2.83
  const double a0 = delta0 + std::pow(g * l, 2) * delta1;
  EXPECT_NEAR(out->advantages[1][0].item<double>(), delta1, 1e-12);
  EXPECT_NEAR(out->advantages[0][0].item<double>(), a0, 1e-12);
  EXPECT_NEAR(out->returns[0][0].item<double>(), a0 + 2, 1e-12);
  EXPECT_NEAR(delta0, 2.83, 1e-12);
}

TEST(FamilyVariableStepGaeTest, OneLongStepEqualsTwoUnitStepsAtLambdaOne) {
  // A step of dphi 2 at rate r is two unit steps at rate r: with lambda 1 the intermediate value
  // cancels, so the first row's return is the same.
  const double g = 0.95;
  absl::StatusOr<Advantages> two = ComputeVariableStepGae(OneEnv({0.7, 0.7}, {0, 0}, {1, 1}, {1.0, 5.0}, 3.0), g, 1.0);
  absl::StatusOr<Advantages> one = ComputeVariableStepGae(OneEnv({0.7}, {0}, {2}, {1.0}, 3.0), g, 1.0);
  ASSERT_TRUE(two.ok() && one.ok());
  EXPECT_NEAR(two->returns[0][0].item<double>(), one->returns[0][0].item<double>(), 1e-12);
  EXPECT_NEAR(one->returns[0][0].item<double>(), 0.7 * (1 + g) + g * g * 3.0, 1e-12);
}

TEST(FamilyVariableStepGaeTest, FailureStopsTheBootstrapTimeOutBootstraps) {
  const double g = 0.9;
  VariableStepRollout r = OneEnv({1, 1}, {0, 0}, {0.5, 1}, {2, 3}, 4);
  r.terminated = D({1, 0}, 2, 1);  // step 0 failed: no V(s_1), no A_1
  absl::StatusOr<Advantages> failed = ComputeVariableStepGae(r, g, 0.95);
  ASSERT_TRUE(failed.ok());
  const double w = (std::pow(g, 0.5) - 1) / (g - 1);
  EXPECT_NEAR(failed->advantages[0][0].item<double>(), w - 2, 1e-12);
  r.terminated = torch::zeros({2, 1}, torch::kFloat64);
  r.truncated = D({1, 0}, 2, 1);  // step 0 timed out in a state of value 10
  r.timeout_values = D({10, -99}, 2, 1);
  absl::StatusOr<Advantages> timed_out = ComputeVariableStepGae(r, g, 0.95);
  ASSERT_TRUE(timed_out.ok());
  EXPECT_NEAR(timed_out->advantages[0][0].item<double>(), w + std::pow(g, 0.5) * 10 - 2, 1e-12);
  // row 1 is its own episode either way
  EXPECT_NEAR(timed_out->advantages[1][0].item<double>(), 1 + g * 4 - 3, 1e-12);
}

TEST(FamilyVariableStepGaeTest, ConstantStepIsOrdinaryGaeExactly) {
  torch::manual_seed(3);
  const int64_t T = 16, N = 8;
  const double g = 0.95, l = 0.95;
  VariableStepRollout r;
  r.continuous_reward = torch::randn({T, N}, torch::kFloat64);
  r.spike_reward = torch::zeros({T, N}, torch::kFloat64);
  r.phase_step = torch::ones({T, N}, torch::kFloat64);
  r.values = torch::randn({T, N}, torch::kFloat64);
  const torch::Tensor ends = torch::rand({T, N}, torch::kFloat64);
  r.terminated = (ends < 0.1).to(torch::kFloat64);
  r.truncated = (ends > 0.9).to(torch::kFloat64);
  r.timeout_values = torch::randn({T, N}, torch::kFloat64);
  r.last_values = torch::randn({N}, torch::kFloat64);
  absl::StatusOr<Advantages> ours = ComputeVariableStepGae(r, g, l);
  ASSERT_TRUE(ours.ok()) << ours.status();
  // The trainer's treatment (trainer_update.cc): a time-out's bootstrap folded into its reward.
  torch::Tensor adv, ret;
  ComputeGae(r.continuous_reward + g * r.timeout_values * r.truncated, r.values, r.terminated + r.truncated, r.last_values,
             g, l, &adv, &ret);
  EXPECT_TRUE(torch::equal(ours->advantages, adv)) << (ours->advantages - adv).abs().max();
  EXPECT_TRUE(torch::equal(ours->returns, ret));
  // and a slower pace changes it: the step length is not ignored
  r.phase_step = torch::full({T, N}, 1.5, torch::kFloat64);
  absl::StatusOr<Advantages> slower = ComputeVariableStepGae(r, g, l);
  ASSERT_TRUE(slower.ok());
  EXPECT_GT((slower->advantages - adv).abs().max().item<double>(), 1e-3);
}

TEST(FamilyVariableStepGaeTest, KeepsTheValuesDtype) {
  VariableStepRollout r = OneEnv({1}, {0}, {1}, {0}, 0);
  r.values = r.values.to(torch::kFloat32);
  absl::StatusOr<Advantages> out = ComputeVariableStepGae(r, 0.9, 0.9);
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out->advantages.scalar_type(), torch::kFloat32);
  EXPECT_FLOAT_EQ(out->advantages[0][0].item<float>(), 1.0f);
}

TEST(FamilyVariableStepGaeTest, RefusesBadInputNamingTheField) {
  const auto message = [](const VariableStepRollout& r, double g = 0.9, double l = 0.9) {
    absl::StatusOr<Advantages> out = ComputeVariableStepGae(r, g, l);
    EXPECT_FALSE(out.ok());
    EXPECT_EQ(out.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(out.status().message());
  };
  VariableStepRollout r = OneEnv({1, 1}, {0, 0}, {1, 1}, {0, 0}, 0);
  EXPECT_THAT(message(r, 1.0), ::testing::HasSubstr("gamma 1"));
  EXPECT_THAT(message(r, 0.9, -0.1), ::testing::HasSubstr("lambda -0.1"));
  VariableStepRollout bad = r;
  bad.phase_step = D({1, 0}, 2, 1);
  EXPECT_THAT(message(bad), ::testing::HasSubstr("phase_step has an entry <= 0"));
  bad = r;
  bad.phase_step = D({1, NAN}, 2, 1);
  EXPECT_THAT(message(bad), ::testing::HasSubstr("phase_step has a non-finite entry"));
  bad = r;
  bad.spike_reward = torch::zeros({3, 1}, torch::kFloat64);
  EXPECT_THAT(message(bad), ::testing::HasSubstr("spike_reward is [3, 1], expected [2, 1]"));
  bad = r;
  bad.truncated = torch::zeros({2, 1}, torch::kFloat64);
  EXPECT_THAT(message(bad), ::testing::HasSubstr("truncated and timeout_values come together"));
  bad = r;
  bad.last_values = torch::zeros({2}, torch::kFloat64);
  EXPECT_THAT(message(bad), ::testing::HasSubstr("last_values is [2], expected [1]"));
}

}  // namespace
}  // namespace modskill::learner::family
