// Every importable format yields a grounded, kinematically consistent clip, the pitch of its
// stance feet is measured, and clips get their default names from their files.
#include "server/core/motion/motion_import.h"
#include "server/core/motion/stance_feet.h"

#include "tests/motion_import_fixtures.h"

namespace modskill {
namespace {

// ---------------------------------------------------------------------------------------------
// 4. Grounding and 5. kinematic consistency, for every importable format.

class ImportedClipTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    std::string path = GetParam();
    if (path == "amass") {
      path = TempPath("smpl.npz");
      WriteAmassNpz(path, {});
    } else if (path == "amass_smplh") {
      path = TempPath("smplh.npz");
      AmassOptions options;
      options.smplh = true;
      WriteAmassNpz(path, options);
    }
    auto clip = ImportMotionFile(path, Spec());
    ASSERT_TRUE(clip.ok()) << clip.status();
    clip_ = *std::move(clip);
  }
  MotionClip clip_;
};

TEST_P(ImportedClipTest, LowestGeometryTouchesTheGround) {
  ASSERT_GE(clip_.num_frames, 2);
  double lowest_over_clip = std::numeric_limits<double>::infinity();
  for (int f = 0; f < clip_.num_frames; ++f) {
    const double lowest = LowestGeomPoint(Spec(), clip_, f);
    EXPECT_GE(lowest, -1e-6) << "frame " << f;
    lowest_over_clip = std::min(lowest_over_clip, lowest);
  }
  EXPECT_NEAR(lowest_over_clip, 0.0, 1e-6);
}

// Positions and rotations from forward kinematics, differentiated numerically, must agree
// with body_vel / body_ang_vel (the root's are central differences by definition; the other
// bodies' are propagated through the hinges). Central differences only approximate the
// derivative where the motion is smooth: the source data has jerks (the DeepMimic walk turns
// its root by 0.125 rad and its left shoulder by 0.5 rad between frames 18 and 19), so each
// sample's tolerance also grows with how much its backward and forward differences disagree,
// and at least 90% of the samples must meet the plain tolerance (10% or 0.05 m/s, 0.1 rad/s).
TEST_P(ImportedClipTest, BodyVelocitiesMatchFiniteDifferences) {
  const int nb = clip_.num_bodies, frames = clip_.num_frames;
  ASSERT_GE(frames, 8);
  ASSERT_EQ(clip_.body_vel.size(), static_cast<size_t>(frames) * nb);
  ASSERT_EQ(clip_.body_ang_vel.size(), static_cast<size_t>(frames) * nb);
  const double dt = 1.0 / clip_.fps;
  double largest_speed = 0, largest_spin = 0;
  int samples = 0, strict_linear = 0, strict_angular = 0;
  for (int f = frames / 4; f < 3 * frames / 4; ++f) {
    for (int b = 0; b < nb; ++b) {
      const Vec3& p0 = clip_.body_pos[(f - 1) * nb + b];
      const Vec3& p1 = clip_.body_pos[f * nb + b];
      const Vec3& p2 = clip_.body_pos[(f + 1) * nb + b];
      const Vec3 difference = (p2 - p0) / (2 * dt);
      const double linear_jerk = ((p2 - p1) / dt - (p1 - p0) / dt).norm();
      const Vec3& velocity = clip_.body_vel[f * nb + b];
      const double linear_error = (velocity - difference).norm();
      const double linear_tolerance = std::max(0.05, 0.1 * difference.norm());
      largest_speed = std::max(largest_speed, difference.norm());

      const Quat& q0 = clip_.body_rot[(f - 1) * nb + b];
      const Quat& q1 = clip_.body_rot[f * nb + b];
      const Quat& q2 = clip_.body_rot[(f + 1) * nb + b];
      const Vec3 angular_difference = AngularVelocity(q0, q2, 2 * dt);
      const double angular_jerk = (AngularVelocity(q1, q2, dt) - AngularVelocity(q0, q1, dt)).norm();
      const Vec3& angular = clip_.body_ang_vel[f * nb + b];
      const double angular_error = (angular - angular_difference).norm();
      const double angular_tolerance = std::max(0.1, 0.1 * angular_difference.norm());
      largest_spin = std::max(largest_spin, angular_difference.norm());

      ++samples;
      strict_linear += linear_error < linear_tolerance;
      strict_angular += angular_error < angular_tolerance;
      if (b == 0) {  // the root: exactly the central differences
        EXPECT_LT(linear_error, 1e-9) << "frame " << f;
        EXPECT_LT(angular_error, 1e-9) << "frame " << f;
      }
      EXPECT_LT(linear_error, linear_tolerance + 0.5 * linear_jerk)
          << Spec().body(b).name << " frame " << f << ": body_vel " << velocity.transpose()
          << ", finite difference " << difference.transpose();
      EXPECT_LT(angular_error, angular_tolerance + 0.5 * angular_jerk)
          << Spec().body(b).name << " frame " << f << ": body_ang_vel " << angular.transpose()
          << ", finite difference " << angular_difference.transpose();
    }
  }
  EXPECT_GE(strict_linear, 0.9 * samples) << strict_linear << " of " << samples;
  EXPECT_GE(strict_angular, 0.9 * samples) << strict_angular << " of " << samples;
  // The clip moves: the comparisons above are not between zeros.
  EXPECT_GT(largest_speed, 0.5);
  EXPECT_GT(largest_spin, 1.0);
}

INSTANTIATE_TEST_SUITE_P(AllFormats, ImportedClipTest,
                         ::testing::Values(kCmuBvh, kDeepMimicWalk, std::string("amass"),
                                           std::string("amass_smplh")),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           const std::string& p = info.param;
                           if (absl::EndsWith(p, ".bvh")) return std::string("CmuBvh");
                           if (absl::EndsWith(p, ".txt")) return std::string("DeepMimic");
                           return p == "amass" ? std::string("AmassSmpl") : std::string("AmassSmplh");
                         });

// ---------------------------------------------------------------------------------------------
// 7. Default clip names.

TEST(DefaultClipName, ByFormat) {
  EXPECT_EQ(DefaultClipName("humanoid3d_walk.txt"), "deepmimic_walk");
  EXPECT_EQ(DefaultClipName("/data/deepmimic/humanoid3d_spinkick.txt"), "deepmimic_spinkick");
  EXPECT_EQ(DefaultClipName("02_01.bvh"), "cmu_02_01");
  EXPECT_EQ(DefaultClipName("/data/cmu/131_01.bvh"), "cmu_131_01");
  EXPECT_EQ(DefaultClipName("foo.npz"), "foo");
  EXPECT_EQ(DefaultClipName("/amass/ACCAD/walk_poses.npz"), "walk_poses");
}

// ---------------------------------------------------------------------------------------------
// 8. Stance feet: a foot that carries the body lies flat.

// Two frames of the rest pose on the ground, both ankles turned by `pitch_deg` (toe up > 0).
MotionClip StandingClip(double pitch_deg) {
  const HumanoidSpec& spec = Spec();
  MotionClip clip;
  clip.num_frames = 2;
  clip.num_bodies = spec.num_bodies();
  clip.root_pos.assign(2, Vec3(0, 0, 1));
  clip.local_rot.assign(2 * clip.num_bodies, Quat::Identity());
  // About +y a positive angle lowers +x (the toe): toe up is a negative angle.
  const Quat tilt(Eigen::AngleAxisd(-pitch_deg * kPi / 180, Vec3::UnitY()));
  for (int f = 0; f < 2; ++f) {
    for (const char* ankle : {"L_Ankle", "R_Ankle"}) clip.local(f, spec.BodyIndex(ankle)) = tilt;
  }
  EXPECT_TRUE(PlaceOnGround(spec, &clip).ok());
  return clip;
}

TEST(StanceFeet, MeasuresTheSolePitchOfFeetOnTheFloor) {
  const StanceFeet flat = MeasureStanceFeet(Spec(), StandingClip(0));
  EXPECT_EQ(flat.stance_samples, 4);  // 2 frames x 2 feet
  EXPECT_NEAR(flat.mean_pitch_deg, 0, 1e-6);
  EXPECT_NEAR(flat.mean_clearance, 0, 0.002);  // SMPL's right foot sits ~1 mm higher at rest
  const StanceFeet toe_up = MeasureStanceFeet(Spec(), StandingClip(8));
  EXPECT_EQ(toe_up.stance_samples, 4);
  EXPECT_NEAR(toe_up.mean_pitch_deg, 8, 1e-6);
  // A foot lifted off the floor (and one not slowed down) is not in stance.
  MotionClip lifted = StandingClip(0);
  for (int f = 0; f < 2; ++f) {
    for (const char* body : {"L_Ankle", "L_Toe"}) lifted.body_pos[f * lifted.num_bodies + Spec().BodyIndex(body)].z() += 0.1;
  }
  EXPECT_EQ(MeasureStanceFeet(Spec(), lifted).stance_samples, 2);
  MotionClip moving = StandingClip(0);
  for (int f = 0; f < 2; ++f) moving.body_vel[f * moving.num_bodies + Spec().BodyIndex("R_Ankle")] = Vec3(1, 0, 0);
  EXPECT_EQ(MeasureStanceFeet(Spec(), moving).stance_samples, 2);
}

}  // namespace
}  // namespace modskill
