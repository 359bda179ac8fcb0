// The episode fitness F (common/policy/family_fitness.h): hand-computed terms, the drag threshold V,
// and refusals.
#include "common/policy/family_fitness.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace modskill {
namespace {

TEST(FamilyFitnessTest, PerfectEpisodeIsOnePlusTheConstraint) {
  FitnessAccumulator acc;
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(acc.AddFrame({}).ok());
  absl::StatusOr<Fitness> f = acc.Finish(0.5);
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_DOUBLE_EQ(f->value, 1.0 + 0.1 * 0.5);
}

TEST(FamilyFitnessTest, HandComputedTerms) {
  FitnessAccumulator acc;
  const std::vector<double> feet_a = {0.2, 1.5};  // one foot slips 1.0 m/s beyond V = 0.5
  const std::vector<double> feet_b = {0.9};       // 0.4 beyond V
  ASSERT_TRUE(acc.AddFrame({1.0, 50.0, 1, feet_a}).ok());
  ASSERT_TRUE(acc.AddFrame({3.0, 100.0, 0, feet_b}).ok());
  absl::StatusOr<Fitness> f = acc.Finish(1.0);
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_NEAR(f->f_pose, std::exp(-2.0 / 2.67), 1e-12);       // mean pose error 2
  EXPECT_NEAR(f->f_velocity, std::exp(-75.0 / 75.5), 1e-12);  // mean velocity error 75
  EXPECT_NEAR(f->f_contact, std::exp(-0.5 / 1.3), 1e-12);     // one mismatch in two frames
  EXPECT_NEAR(f->f_drag, std::exp(-0.7 / 0.7), 1e-12);        // (1.0 + 0.4) / 2 = 0.7 m/s
  EXPECT_NEAR(f->value, f->f_pose * f->f_velocity * f->f_contact * f->f_drag + 0.1, 1e-12);
  EXPECT_EQ(acc.frames(), 2);
}

TEST(FamilyFitnessTest, WorseMotionIsLessFitAndLengthDoesNotMatter) {
  const auto fitness = [](double pose, int frames) {
    FitnessAccumulator acc;
    for (int i = 0; i < frames; ++i) EXPECT_TRUE(acc.AddFrame({pose, 0, 0, {}}).ok());
    return acc.Finish(0).value().value;
  };
  EXPECT_GT(fitness(0.5, 30), fitness(1.0, 30));
  EXPECT_DOUBLE_EQ(fitness(0.5, 30), fitness(0.5, 60));  // a slower time warp is not punished
}

TEST(FamilyFitnessTest, RefusesBadMeasurements) {
  FitnessAccumulator acc;
  EXPECT_EQ(acc.Finish(0).status().code(), absl::StatusCode::kFailedPrecondition);
  absl::Status s = acc.AddFrame({-1, 0, 0, {}});
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), ::testing::HasSubstr("pose_error -1"));
  const std::vector<double> nan_foot = {NAN};
  EXPECT_THAT(std::string(acc.AddFrame({0, 0, 0, nan_foot}).message()), ::testing::HasSubstr("contact_foot_speeds"));
  EXPECT_THAT(std::string(acc.AddFrame({0, INFINITY, 0, {}}).message()), ::testing::HasSubstr("velocity_error"));
  EXPECT_EQ(acc.frames(), 0);  // refused frames are not counted
  ASSERT_TRUE(acc.AddFrame({}).ok());
  EXPECT_THAT(std::string(acc.Finish(1.5).status().message()), ::testing::HasSubstr("r_constraint 1.5"));
}

}  // namespace
}  // namespace modskill
