// Motion splicing (modskill-motion splice): the base's body and travel with some parts' motion from
// another clip, on the shipped clips.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/motion/motion_splice.h"
#include "server/core/sim/part_layout.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

std::vector<int> ArmBodies() {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  EXPECT_TRUE(catalog.ok()) << catalog.status();
  auto layout = catalog->Get("5part");
  EXPECT_TRUE(layout.ok()) << layout.status();
  std::vector<int> bodies;
  for (const BodyPart& part : layout->parts) {
    if (part.name == "L_Arm" || part.name == "R_Arm") bodies.insert(bodies.end(), part.bodies.begin(), part.bodies.end());
  }
  return bodies;
}

bool IsIn(const std::vector<int>& bodies, int body) {
  return std::find(bodies.begin(), bodies.end(), body) != bodies.end();
}

double QuatDistance(const Quat& a, const Quat& b) { return RotationAngle(a.conjugate() * b); }

TEST(MotionSpliceTest, KeepsTheBasesBodyAndTravelAndTakesThePartsFromTheSource) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  const MotionClip& jog = ShippedClip("deepmimic_jog");
  const std::vector<int> arms = ArmBodies();
  SpliceRequest request{"walk_with_jog_arms", arms, SpliceTiming::kStretch};
  auto spliced = SpliceParts(DefaultSpec(), walk, jog, request);
  ASSERT_TRUE(spliced.ok()) << spliced.status();
  ASSERT_EQ(spliced->num_frames, walk.num_frames);
  EXPECT_EQ(spliced->name, "walk_with_jog_arms");
  EXPECT_NE(spliced->source.find("deepmimic_jog"), std::string::npos) << spliced->source;
  const double lift = spliced->root_pos[0].z() - walk.root_pos[0].z();
  for (int f = 0; f < walk.num_frames; ++f) {
    EXPECT_NEAR(spliced->root_pos[f].x(), walk.root_pos[f].x(), 1e-12);
    EXPECT_NEAR(spliced->root_pos[f].y(), walk.root_pos[f].y(), 1e-12);
    // The floor is found again frame by frame (floor_height.h) on a clip already on it: it moves
    // a few millimetres, not more.
    EXPECT_NEAR(spliced->root_pos[f].z() - walk.root_pos[f].z(), lift, 0.005) << "frame " << f;
    for (int b = 0; b < walk.num_bodies; ++b) {
      if (IsIn(arms, b)) continue;
      EXPECT_EQ(spliced->local(f, b).coeffs(), walk.local(f, b).coeffs()) << "frame " << f << " body " << b;
    }
  }
  // Stretched: the source's first and last frames land on the base's first and last.
  double arms_moved = 0;
  for (int b : arms) {
    EXPECT_LT(QuatDistance(spliced->local(0, b), jog.local(0, b)), 1e-6);
    EXPECT_LT(QuatDistance(spliced->local(walk.num_frames - 1, b), jog.local(jog.num_frames - 1, b)), 1e-6);
    arms_moved += QuatDistance(spliced->local(walk.num_frames / 2, b), walk.local(walk.num_frames / 2, b));
  }
  EXPECT_GT(arms_moved, 0.1) << "the jog's arms should differ from the walk's";
  // Kinematics follow: an arm hinge's angle is the source's, a leg's the base's.
  const int elbow_hinge = 3 * (DefaultSpec().BodyIndex("R_Elbow") - 1);
  const int knee_hinge = 3 * (DefaultSpec().BodyIndex("R_Knee") - 1);
  const int hinges = spliced->num_hinges();
  EXPECT_NEAR(spliced->dof_pos[elbow_hinge], jog.dof_pos[elbow_hinge], 1e-6);
  EXPECT_NEAR(spliced->dof_pos[hinges * 5 + knee_hinge], walk.dof_pos[hinges * 5 + knee_hinge], 1e-6);
}

TEST(MotionSpliceTest, ClipTimingPlaysTheSourceAtItsOwnSpeedAndHoldsItsEnd) {
  const MotionClip& punch = ShippedClip("deepmimic_punch");  // 64 frames
  const MotionClip& walk = ShippedClip("deepmimic_walk");    // 38 frames
  const std::vector<int> arms = ArmBodies();
  auto spliced = SpliceParts(DefaultSpec(), punch, walk, {"punch_with_walk_arms", arms, SpliceTiming::kClip});
  ASSERT_TRUE(spliced.ok()) << spliced.status();
  ASSERT_GT(punch.num_frames, walk.num_frames);
  for (int f = 0; f < punch.num_frames; ++f) {
    const int source_frame = std::min(f, walk.num_frames - 1);
    for (int b : arms) {
      EXPECT_LT(QuatDistance(spliced->local(f, b), walk.local(source_frame, b)), 1e-6) << "frame " << f;
    }
  }
}

TEST(MotionSpliceTest, HoldTimingReachesOneSourcePoseFromTheBaseAndHoldsIt) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");    // the base: 38 frames at 30 fps
  const MotionClip& punch = ShippedClip("deepmimic_punch");  // 64 frames
  const std::vector<int> arms = ArmBodies();
  SpliceRequest request{"walk_holding_punch_arms", arms, SpliceTiming::kHold};
  request.hold_at = 0.5;
  auto spliced = SpliceParts(DefaultSpec(), walk, punch, request);
  ASSERT_TRUE(spliced.ok()) << spliced.status();
  const int ramp_frames = static_cast<int>(walk.fps * kHoldRampSeconds);
  for (int b : arms) {
    // hold_at 0.5 of the punch's 63 frame intervals: frame 31.5
    const Quat held = punch.local(31, b).slerp(0.5, punch.local(32, b)).normalized();
    EXPECT_LT(QuatDistance(spliced->local(0, b), walk.local(0, b)), 1e-6) << "starts on the base's pose";
    for (int f = ramp_frames; f < walk.num_frames; ++f) {
      EXPECT_LT(QuatDistance(spliced->local(f, b), held), 1e-6) << "frame " << f;
    }
    const int mid = ramp_frames / 2;  // halfway up the smoothstep: halfway between the two
    const double to_base = QuatDistance(spliced->local(mid, b), walk.local(mid, b));
    const double to_held = QuatDistance(spliced->local(mid, b), held);
    EXPECT_NEAR(to_base, to_held, 0.05 * (to_base + to_held) + 1e-6) << "body " << b;
  }
  request.hold_at = 1.5;
  auto outside = SpliceParts(DefaultSpec(), walk, punch, request);
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.status().message().find("hold_at 1.5"), std::string::npos) << outside.status();
  EXPECT_TRUE(ParseSpliceTiming("hold").ok());
}

TEST(MotionSpliceTest, RefusesTheRootABadNameAndOtherRates) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  const MotionClip& jog = ShippedClip("deepmimic_jog");
  auto root = SpliceParts(DefaultSpec(), walk, jog, {"x", {0, 1}, SpliceTiming::kStretch});
  ASSERT_FALSE(root.ok());
  EXPECT_NE(root.status().message().find("root body"), std::string::npos) << root.status();
  auto name = SpliceParts(DefaultSpec(), walk, jog, {"../escape", ArmBodies(), SpliceTiming::kStretch});
  ASSERT_FALSE(name.ok());
  EXPECT_NE(name.status().message().find("splice name"), std::string::npos) << name.status();
  auto none = SpliceParts(DefaultSpec(), walk, jog, {"x", {}, SpliceTiming::kStretch});
  EXPECT_FALSE(none.ok());
  MotionClip fast = jog;
  fast.fps = 60;
  auto rate = SpliceParts(DefaultSpec(), walk, fast, {"x", ArmBodies(), SpliceTiming::kStretch});
  ASSERT_FALSE(rate.ok());
  EXPECT_NE(rate.status().message().find("60 fps"), std::string::npos) << rate.status();
  auto timing = ParseSpliceTiming("loop");
  ASSERT_FALSE(timing.ok());
  EXPECT_NE(timing.status().message().find("'loop'"), std::string::npos);
  EXPECT_TRUE(ParseSpliceTiming("clip").ok());
}

}  // namespace
}  // namespace modskill
