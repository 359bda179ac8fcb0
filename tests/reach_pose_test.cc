// Held reach poses (modskill-motion reach): inverse kinematics brings the right hand to a target
// in the reach task's frame and the clip holds it there, on a shipped clip.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/motion/motion_splice.h"
#include "server/core/motion/reach_pose.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

ReachPoseRequest RightArmRequest(const Vec3& target) {
  const HumanoidSpec& spec = DefaultSpec();
  ReachPoseRequest request;
  request.name = "reach_test";
  request.hand = spec.BodyIndex("R_Hand");
  for (const char* body : {"R_Thorax", "R_Shoulder", "R_Elbow", "R_Wrist", "R_Hand"}) {
    request.moved_bodies.push_back(spec.BodyIndex(body));
  }
  request.target = target;
  return request;
}

// The target in the world at `frame`, as ReachTask draws it: heading frame on the root's ground point.
Vec3 WorldTarget(const MotionClip& clip, int frame, const Vec3& target) {
  Vec3 ground = clip.body_pos[frame * clip.num_bodies];
  ground.z() = 0;
  return ground + HeadingRotation(clip.body_rot[frame * clip.num_bodies]) * target;
}

TEST(ReachPoseTest, BringsTheHandToAReachableTargetAndHoldsIt) {
  const HumanoidSpec& spec = DefaultSpec();
  const MotionClip& walk = ShippedClip("deepmimic_walk");  // 38 frames: ramp to frame 30, then held
  const Vec3 target(0.35, -0.35, 1.3);                     // in front of the right shoulder
  const ReachPoseRequest request = RightArmRequest(target);
  auto pose = MakeReachPose(spec, walk, request);
  ASSERT_TRUE(pose.ok()) << pose.status();
  const MotionClip& clip = pose->clip;
  const int held = static_cast<int>(walk.fps * kHoldRampSeconds), hand = request.hand;
  EXPECT_LT(pose->distance, 0.01);
  const Vec3 at_held = clip.body_pos[held * clip.num_bodies + hand];
  EXPECT_LT((at_held - WorldTarget(clip, held, target)).norm(), 0.01);
  const Vec3 at_start = clip.body_pos[hand];
  EXPECT_GT((at_start - WorldTarget(clip, 0, target)).norm(), 0.2) << "the walk's hand does not start there";
  for (int b = 0; b < spec.num_bodies(); ++b) {
    const bool moved = std::find(request.moved_bodies.begin(), request.moved_bodies.end(), b) !=
                       request.moved_bodies.end();
    EXPECT_LT(RotationAngle(clip.local(0, b).conjugate() * walk.local(0, b)), 1e-6) << "frame 0 is the base's";
    if (!moved) {
      EXPECT_LT(RotationAngle(clip.local(held, b).conjugate() * walk.local(held, b)), 1e-6) << spec.body(b).name;
    }
  }
  for (int f = held; f < clip.num_frames; ++f) {
    for (int b : request.moved_bodies) {
      EXPECT_LT(RotationAngle(clip.local(f, b).conjugate() * clip.local(held, b)), 1e-6) << "held, frame " << f;
    }
  }
}

TEST(ReachPoseTest, OutOfReachStretchesTowardTheTargetWithinTheJointRanges) {
  const HumanoidSpec& spec = DefaultSpec();
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  const Vec3 target(1.5, -0.5, 1.2);  // 1.5 m ahead: no arm gets there standing
  const ReachPoseRequest request = RightArmRequest(target);
  auto pose = MakeReachPose(spec, walk, request);
  ASSERT_TRUE(pose.ok()) << pose.status();
  const int held = static_cast<int>(walk.fps * kHoldRampSeconds);
  const Vec3 shoulder = pose->clip.body_pos[held * walk.num_bodies + spec.BodyIndex("R_Shoulder")];
  const double shoulder_to_target = (WorldTarget(pose->clip, held, target) - shoulder).norm();
  EXPECT_GT(pose->distance, 0.5);
  // Stretched: the hand is nearly an arm's length closer to the target than the shoulder is.
  EXPECT_LT(pose->distance, shoulder_to_target - 0.45);
  for (int b : request.moved_bodies) {
    const Vec3 angles = HingeAngles(pose->clip.local(held, b));
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(angles[k], spec.body(b).range_low[k] - 1e-6) << spec.body(b).name << " hinge " << k;
      EXPECT_LE(angles[k], spec.body(b).range_high[k] + 1e-6) << spec.body(b).name << " hinge " << k;
    }
  }
}

TEST(ReachPoseTest, RefusesBodiesOffTheHandsChainAndBadNames) {
  const HumanoidSpec& spec = DefaultSpec();
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  ReachPoseRequest request = RightArmRequest(Vec3(0.3, -0.3, 1.2));
  request.moved_bodies.push_back(spec.BodyIndex("L_Elbow"));
  auto off_chain = MakeReachPose(spec, walk, request);
  ASSERT_FALSE(off_chain.ok());
  EXPECT_NE(off_chain.status().message().find("'L_Elbow' is not 'R_Hand' or a non-root ancestor"), std::string::npos)
      << off_chain.status();
  request = RightArmRequest(Vec3(0.3, -0.3, 1.2));
  request.name = "../x";
  EXPECT_FALSE(MakeReachPose(spec, walk, request).ok());
  request = RightArmRequest(Vec3(0.3, -0.3, std::nan("")));
  auto not_finite = MakeReachPose(spec, walk, request);
  ASSERT_FALSE(not_finite.ok());
  EXPECT_NE(not_finite.status().message().find("target is not finite"), std::string::npos) << not_finite.status();
  MotionClip one_frame = walk;
  one_frame.num_frames = 1;
  auto too_short = MakeReachPose(spec, one_frame, RightArmRequest(Vec3(0.3, -0.3, 1.2)));
  ASSERT_FALSE(too_short.ok());
  EXPECT_NE(too_short.status().message().find("reach pose: clip 'deepmimic_walk' has 24 bodies and 1 frames"),
            std::string::npos)
      << too_short.status();
}

}  // namespace
}  // namespace modskill
