// The floor under a clip (floor_height.h, PlaceOnGround): contacts rest on z = 0 frame by frame,
// flights keep their height, no frame ends in the ground; and on the shipped CMU walk, whose
// retargeted contacts drifted up 6 cm over 2.8 s, every frame now keeps a foot on the floor.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/motion/floor_height.h"
#include "server/core/motion/motion_import.h"
#include "tests/motion_import_fixtures.h"

namespace modskill {
namespace {

constexpr double kFps = 30;

TEST(FloorHeightTest, AConstantHeightIsTheFloor) {
  const std::vector<double> lowest(90, 0.05);
  for (double floor : FloorHeights(lowest, kFps)) EXPECT_NEAR(floor, 0.05, 1e-12);
}

TEST(FloorHeightTest, ASlowDriftIsFollowed) {
  // A walk whose contacts rise 2 cm per second, as CMU 02_01's did.
  std::vector<double> lowest;
  for (int f = 0; f < 120; ++f) lowest.push_back(0.02 * f / kFps);
  const std::vector<double> floor = FloorHeights(lowest, kFps);
  for (int f = 0; f < 120; ++f) {
    EXPECT_GE(lowest[f] - floor[f], -1e-12) << "frame " << f;
    EXPECT_LT(lowest[f] - floor[f], 0.006) << "frame " << f;  // a constant shift leaves up to 8 cm
  }
}

TEST(FloorHeightTest, AFlightKeepsItsHeight) {
  // On the floor, then 0.4 s in the air with a 0.5 m apex (a backflip's is 1 m over 0.5 s).
  std::vector<double> lowest(90, 0.0);
  for (int f = 30; f < 42; ++f) {
    const double t = (f - 29.5) / 12.5;
    lowest[f] = 2.0 * t * (1 - t);
  }
  const std::vector<double> floor = FloorHeights(lowest, kFps);
  const double apex = *std::max_element(lowest.begin(), lowest.end());
  for (int f = 0; f < 90; ++f) EXPECT_NEAR(floor[f], 0.0, 1e-12) << "frame " << f;
  EXPECT_GT(apex, 0.49);
}

TEST(FloorHeightTest, NoFrameEndsInTheGroundAndTheLowestTouches) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> noise(-0.03, 0.03);
  std::vector<double> lowest;
  for (int f = 0; f < 200; ++f) lowest.push_back(0.1 + 0.05 * std::sin(f / 20.0) + noise(rng));
  lowest[77] = -0.2;  // a glitched frame deep below the rest
  const std::vector<double> floor = FloorHeights(lowest, kFps);
  double clearance = 1e9;
  for (int f = 0; f < 200; ++f) {
    EXPECT_LE(floor[f], lowest[f] + 1e-12) << "frame " << f;
    clearance = std::min(clearance, lowest[f] - floor[f]);
  }
  EXPECT_NEAR(clearance, 0.0, 1e-12);
  // The glitch pulls the floor down around it, not over the whole clip.
  EXPECT_GT(floor[10], 0.0);
  EXPECT_GT(floor[190], 0.0);
}

TEST(FloorHeightTest, AHighFrameRateFollowsTheSameDrift) {
  // 10 s at 10,000 fps (an import's largest rate): windows of 10,001 frames are read at a stride.
  const double fps = 10000;
  std::vector<double> lowest;
  for (int f = 0; f < 100000; ++f) lowest.push_back(0.02 * f / fps + 0.001 * std::sin(f / 300.0));
  const std::vector<double> floor = FloorHeights(lowest, fps);
  for (int f = 0; f < 100000; f += 997) {
    EXPECT_GE(lowest[f] - floor[f], -1e-12) << "frame " << f;
    EXPECT_LT(lowest[f] - floor[f], 0.008) << "frame " << f;
  }
}

TEST(FloorHeightTest, TheShippedCmuWalkKeepsAFootOnTheFloor) {
  auto clip = ImportMotionFile(kCmuBvh, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  double highest = 0;
  for (int f = 0; f < clip->num_frames; ++f) highest = std::max(highest, LowestGeomPoint(Spec(), *clip, f));
  // One constant shift left the walk's last second 4-6 cm above the floor.
  EXPECT_LT(highest, 0.025);
  EXPECT_DOUBLE_EQ(FootContactRatio(Spec(), *clip), 1.0);
}

TEST(PinFloorToStanceTest, StanceFramesRestOnTheirLowestPointAndGapsInterpolate) {
  // A window floor at 0; the lowest point bobs 0-2 cm as a retargeted walk's does.
  const std::vector<double> floor(7, 0.0);
  const std::vector<double> lowest = {0.010, 0.020, 0.200, 0.300, 0.200, 0.004, 0.012};
  const std::vector<bool> stance = {false, true, false, false, false, true, false};
  const std::vector<double> pinned = PinFloorToStance(floor, lowest, stance);
  EXPECT_NEAR(pinned[0], 0.010, 1e-12);  // before the first anchor the offset holds (capped by its lowest)
  EXPECT_NEAR(pinned[1], 0.020, 1e-12);  // anchors: on their lowest point
  EXPECT_NEAR(pinned[5], 0.004, 1e-12);
  EXPECT_NEAR(pinned[3], 0.012, 1e-12);  // a flight: halfway between the anchors' offsets
  EXPECT_NEAR(pinned[6], 0.004, 1e-12);  // after the last anchor the offset holds
  for (size_t f = 0; f < lowest.size(); ++f) EXPECT_LE(pinned[f], lowest[f]) << "frame " << f;
  EXPECT_EQ(PinFloorToStance(floor, lowest, std::vector<bool>(7, false)), floor);
}

TEST(PinFloorToStanceTest, TheDeepMimicWalkRestsOnItsStanceFootAndTheJumpStillFlies) {
  ImportOptions options;
  options.floor = FloorMode::kStance;
  auto walk = ImportMotionFile(kDeepMimicWalk, Spec(), options);
  ASSERT_TRUE(walk.ok()) << walk.status();
  // The window floor leaves this walk's lowest point 12 mm up on average, 26 mm at most.
  double clearance = 0, highest = 0;
  for (int f = 0; f < walk->num_frames; ++f) {
    const double lowest = LowestGeomPoint(Spec(), *walk, f);
    EXPECT_GE(lowest, -1e-9) << "frame " << f;
    clearance += lowest / walk->num_frames;
    highest = std::max(highest, lowest);
  }
  EXPECT_LT(clearance, 0.003);
  EXPECT_LT(highest, 0.015);
  const std::string jump_path = std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_jump.txt";
  auto jump = ImportMotionFile(jump_path, Spec(), options);
  ASSERT_TRUE(jump.ok()) << jump.status();
  double apex = 0;
  for (int f = 0; f < jump->num_frames; ++f) apex = std::max(apex, LowestGeomPoint(Spec(), *jump, f));
  EXPECT_GT(apex, 0.15);  // 0.21 m on the window floor
}

}  // namespace
}  // namespace modskill
