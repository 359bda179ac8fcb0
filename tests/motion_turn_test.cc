// Turning a clip's path (modskill-motion turn): the walk's steps along a bending path, on the
// shipped walk.
#include <cmath>

#include <gtest/gtest.h>

#include "server/core/motion/motion_turn.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

double Heading(const Quat& q) {
  const Vec3 forward = q * Vec3::UnitX();
  return std::atan2(forward.y(), forward.x());
}

double WrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

// Horizontal path length of the root over the clip.
double PathLength(const MotionClip& clip) {
  double length = 0;
  for (int f = 1; f < clip.num_frames; ++f) {
    const Vec3 step = clip.root_pos[f] - clip.root_pos[f - 1];
    length += std::hypot(step.x(), step.y());
  }
  return length;
}

TEST(MotionTurnTest, BendsThePathAndKeepsTheBodyRelativeToTheRoot) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  const double rate = 45 * M_PI / 180;
  auto turned = TurnClip(DefaultSpec(), walk, {"walk_left_45", rate, ""});
  ASSERT_TRUE(turned.ok()) << turned.status();
  ASSERT_EQ(turned->num_frames, walk.num_frames);
  EXPECT_EQ(turned->name, "walk_left_45");
  EXPECT_NE(turned->label.find("turning +45 deg/s"), std::string::npos) << turned->label;
  EXPECT_NE(turned->source.find("deepmimic_walk"), std::string::npos) << turned->source;
  EXPECT_NEAR(PathLength(*turned), PathLength(walk), 1e-9);
  const int nb = walk.num_bodies;
  for (int f = 0; f < walk.num_frames; ++f) {
    const double turn = rate * f / walk.fps;
    EXPECT_NEAR(WrapAngle(Heading(turned->body_rot[f * nb]) - Heading(walk.body_rot[f * nb]) - turn), 0, 1e-9)
        << "frame " << f;
    EXPECT_NEAR(turned->root_pos[f].z(), walk.root_pos[f].z(), 1e-12);
    for (int b = 1; b < nb; ++b) {
      // Every body where the base has it, seen from the root.
      const Vec3 base_local = walk.body_rot[f * nb].conjugate() * (walk.body_pos[f * nb + b] - walk.body_pos[f * nb]);
      const Vec3 turned_local =
          turned->body_rot[f * nb].conjugate() * (turned->body_pos[f * nb + b] - turned->body_pos[f * nb]);
      ASSERT_LT((turned_local - base_local).norm(), 1e-9) << "frame " << f << " body " << b;
    }
  }
  // The walk goes about straight; turned left it ends to the left of where it heads at first.
  const Vec3 forward0 = HeadingRotation(walk.body_rot[0]) * Vec3::UnitX();
  const Vec3 travel = turned->root_pos.back() - turned->root_pos.front();
  EXPECT_GT(forward0.cross(travel).z(), 0.1 * travel.norm());
  const Vec3 base_travel = walk.root_pos.back() - walk.root_pos.front();
  EXPECT_LT(std::abs(forward0.cross(base_travel).z()), 0.1 * base_travel.norm());
}

TEST(MotionTurnTest, ARateOfZeroKeepsTheClip) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  auto same = TurnClip(DefaultSpec(), walk, {"walk_straight", 0.0, ""});
  ASSERT_TRUE(same.ok()) << same.status();
  for (size_t i = 0; i < walk.body_pos.size(); ++i) ASSERT_LT((same->body_pos[i] - walk.body_pos[i]).norm(), 1e-9);
}

TEST(MotionTurnTest, RefusesBadRatesAndNames) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  for (double rate : {std::nan(""), 1.01 * kMaxTurnRate, -4.0, HUGE_VAL}) {
    auto turned = TurnClip(DefaultSpec(), walk, {"x", rate, ""});
    ASSERT_FALSE(turned.ok()) << rate;
    EXPECT_EQ(turned.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(turned.status().message().find("yaw rate"), std::string::npos) << turned.status();
  }
  auto bad_name = TurnClip(DefaultSpec(), walk, {"../x", 0.5, ""});
  ASSERT_FALSE(bad_name.ok());
  EXPECT_NE(bad_name.status().message().find("turn name"), std::string::npos) << bad_name.status();
}

}  // namespace
}  // namespace modskill
