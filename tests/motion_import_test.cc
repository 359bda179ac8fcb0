// Tests of the motion importers (AMASS npz, CMU BVH, DeepMimic) and the native clip format:
// round trips, AMASS semantics, resampling. Grounding and kinematic consistency:
// motion_import_consistency_test.cc; bad input: motion_import_bad_input_test.cc.
#include "server/core/motion/motion_import.h"

#include "tests/motion_import_fixtures.h"

namespace modskill {
namespace {

// ---------------------------------------------------------------------------------------------
// 1. Round trips through the native format.

TEST(MotionImportRoundTrip, CmuBvh) { ExpectRoundTrip(kCmuBvh, "cmu.msclip"); }

// CMU takes start with the actor's calibration pose; the importer drops it, so the clip's first
// frame is already the take (a reset to frame 0 no longer starts from a T-pose).
TEST(CmuCalibrationFrame, IsDroppedAndTheTakeStartsSmoothly) {
  auto bvh = ReadBvhFile(kCmuBvh);
  ASSERT_TRUE(bvh.ok()) << bvh.status();
  EXPECT_EQ(LeadingCalibrationFrames(*bvh), 1);
  BvhClip take = *bvh;  // the same take without its calibration frame has none
  take.num_frames -= 1;
  take.root_translation.erase(take.root_translation.begin());
  take.local_rotation.erase(take.local_rotation.begin(), take.local_rotation.begin() + take.num_joints());
  EXPECT_EQ(LeadingCalibrationFrames(take), 0);
  auto clip = ImportMotionFile(kCmuBvh, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  // Body positions move a few centimetres per frame at 30 fps from the first frame on.
  for (int frame : {0, 1, 40}) {
    double moved = 0;
    for (int b = 0; b < clip->num_bodies; ++b) {
      moved += (clip->body_pos[(frame + 1) * clip->num_bodies + b] - clip->body_pos[frame * clip->num_bodies + b]).norm();
    }
    EXPECT_LT(moved / clip->num_bodies, 0.05) << frame;
  }
}

TEST(MotionImportRoundTrip, DeepMimic) { ExpectRoundTrip(kDeepMimicWalk, "walk.msclip"); }

TEST(MotionImportRoundTrip, AmassSmplFloat32) {
  const std::string npz = TempPath("smpl.npz");
  WriteAmassNpz(npz, {});
  ExpectRoundTrip(npz, "smpl.msclip");
}

TEST(MotionImportRoundTrip, AmassSmplhFloat64WithBetasAndGender) {
  const std::string npz = TempPath("smplh.npz");
  AmassOptions options;
  options.smplh = true;
  WriteAmassNpz(npz, options);
  ExpectRoundTrip(npz, "smplh.msclip");
}

// SMPL-H stores the same 22 body joints first: the body motion equals the SMPL file's.
TEST(MotionImportRoundTrip, SmplhBodyMatchesSmpl) {
  const std::string smpl = TempPath("smpl.npz"), smplh = TempPath("smplh.npz");
  WriteAmassNpz(smpl, {});
  AmassOptions options;
  options.smplh = true;
  WriteAmassNpz(smplh, options);
  auto a = ImportAmassNpz(smpl, Spec());
  auto b = ImportAmassNpz(smplh, Spec());
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_EQ(a->num_frames, b->num_frames);
  for (const char* name : {"L_Hand", "R_Hand"}) {
    for (int f = 0; f < b->num_frames; ++f) {
      EXPECT_LT(QuatDistance(b->local(f, Body(name)), Quat::Identity()), 1e-12) << name << " frame " << f;
    }
  }
  for (int f = 0; f < a->num_frames; ++f) {
    EXPECT_LT((a->root_pos[f] - b->root_pos[f]).norm(), 1e-5);  // float32 vs float64 input
    for (int body = 0; body < a->num_bodies; ++body) {
      if (body == Body("L_Hand") || body == Body("R_Hand")) continue;
      EXPECT_LT(QuatDistance(a->local(f, body), b->local(f, body)), 1e-5) << "frame " << f << " body " << body;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 2. AMASS semantics.

// Zero root orientation: SMPL's template is y-up while AMASS's world is z-up, so the body lies
// along world +y.
TEST(AmassSemantics, ZeroRootOrientationLiesAlongWorldY) {
  const std::string npz = TempPath("zero.npz");
  WriteRootOnlyNpz(npz, std::vector<Vec3>(10, Vec3::Zero()), std::vector<Vec3>(10, Vec3::Zero()), 60.0);
  auto clip = ImportAmassNpz(npz, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  ASSERT_TRUE(ComputeClipKinematics(Spec(), &*clip).ok());
  const int nb = clip->num_bodies;
  for (int f = 0; f < clip->num_frames; ++f) {
    const Vec3 head = clip->body_pos[f * nb + Body("Head")] - clip->body_pos[f * nb];
    EXPECT_GT(head.y(), 0.4) << head.transpose();
    EXPECT_LT(std::abs(head.z()), 0.1) << head.transpose();
  }
}

// Real AMASS data rotates the template upright with the root (pi/2 about x): every body then
// sits at its rest position relative to the pelvis, turned by a yaw only.
TEST(AmassSemantics, UprightRootGivesRestPoseTurnedByYaw) {
  const int n = 40;
  const std::string npz = TempPath("upright.npz");
  WriteRootOnlyNpz(npz, std::vector<Vec3>(n, Vec3(kPi / 2, 0, 0)), std::vector<Vec3>(n, Vec3::Zero()), 60.0);
  auto clip = ImportAmassNpz(npz, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_EQ(clip->num_frames, n);
  EXPECT_DOUBLE_EQ(clip->fps, 60.0);
  ASSERT_TRUE(ComputeClipKinematics(Spec(), &*clip).ok());
  const std::vector<Vec3> rest = Spec().RestPositions();
  const int nb = clip->num_bodies;
  for (int f = 0; f < n; ++f) {
    const Quat pelvis_rot = clip->body_rot[f * nb];
    const Quat yaw = HeadingRotation(pelvis_rot);
    // The pelvis is upright: its rotation is a pure yaw.
    EXPECT_LT(QuatDistance(pelvis_rot, yaw), 1e-9) << "frame " << f;
    const Vec3 pelvis = clip->body_pos[f * nb];
    for (int b = 0; b < nb; ++b) {
      const Vec3 relative = clip->body_pos[f * nb + b] - pelvis;
      EXPECT_LT((relative - yaw * rest[b]).norm(), 1e-9) << Spec().body(b).name << " frame " << f;
    }
    const Vec3 head = clip->body_pos[f * nb + Body("Head")] - pelvis;
    EXPECT_LT(std::abs(head.x()), 0.05) << head.transpose();
    EXPECT_LT(std::abs(head.y()), 0.05) << head.transpose();
    EXPECT_GT(head.z(), 0.4) << head.transpose();
  }
  // SMPL faces +z; the root's pi/2 about x turns +z into world -y: the humanoid faces -y.
  const Vec3 facing = clip->body_rot[0] * Vec3::UnitX();
  EXPECT_LT((facing - Vec3(0, -1, 0)).norm(), 1e-9) << facing.transpose();

  auto resampled = ImportMotionFile(npz, Spec());
  ASSERT_TRUE(resampled.ok()) << resampled.status();
  EXPECT_DOUBLE_EQ(resampled->fps, 30.0);
  EXPECT_NEAR(resampled->duration(), (n - 1) / 60.0, 1.0 / 30.0);
}

// In SMPL the root rotation pivots about the pelvis joint J0: the posed pelvis is J0 + trans
// whatever the root orientation (smplx lbs.batch_rigid_transform: the root transform is
// [R_root | J0]; PHC's AMASS conversion uses trans + J0 as well). Turning, leaning or lying
// down on the spot therefore must not move the pelvis.
TEST(AmassSemantics, RootRotationPivotsAboutThePelvis) {
  const Quat upright(Eigen::AngleAxisd(kPi / 2, Vec3::UnitX()));
  const std::vector<Quat> roots = {
      upright,
      Quat(Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ())) * upright,        // turned left
      Quat(Eigen::AngleAxisd(kPi, Vec3::UnitZ())) * upright,            // turned around
      Quat(Eigen::AngleAxisd(-kPi / 4, Vec3::UnitY())) * upright,       // leaning
      Quat::Identity(),                                                 // lying along +y
  };
  std::vector<Vec3> axis_angles;
  for (const Quat& q : roots) axis_angles.push_back(RotationVector(q));
  const Vec3 trans(0.4, -0.7, 0.9);
  const std::string npz = TempPath("pivot.npz");
  WriteRootOnlyNpz(npz, axis_angles, std::vector<Vec3>(roots.size(), trans), 30.0);
  auto clip = ImportAmassNpz(npz, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  for (int f = 1; f < clip->num_frames; ++f) {
    EXPECT_LT((clip->root_pos[f] - clip->root_pos[0]).norm(), 1e-9)
        << "frame " << f << ": pelvis at " << clip->root_pos[f].transpose() << ", frame 0 at "
        << clip->root_pos[0].transpose();
  }
}

// A knee flexion in SMPL (positive angle about the joint's x axis) bends that knee backward.
TEST(AmassSemantics, KneeFlexionBendsTheLeftShinBackward) {
  const int n = 3;
  std::vector<double> poses(72 * n, 0.0);
  for (int f = 0; f < n; ++f) {
    poses[72 * f] = kPi / 2;      // upright
    poses[72 * f + 3 * 4] = 1.0;  // SMPL joint 4: L_Knee
  }
  NpzWriter writer;
  writer.AddF64("poses", {n, 72}, poses);
  writer.AddF64("trans", {n, 3}, std::vector<double>(3 * n, 0.0));
  writer.AddF64("mocap_framerate", {}, {30.0});
  const std::string npz = TempPath("knee.npz");
  ASSERT_TRUE(writer.Write(npz, false));
  auto clip = ImportAmassNpz(npz, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  ASSERT_TRUE(ComputeClipKinematics(Spec(), &*clip).ok());
  const int nb = clip->num_bodies;
  const Quat to_heading = InverseHeadingRotation(clip->body_rot[0]);
  const Vec3 left_shin = to_heading * (clip->body_pos[Body("L_Ankle")] - clip->body_pos[Body("L_Knee")]);
  const Vec3 right_shin = to_heading * (clip->body_pos[Body("R_Ankle")] - clip->body_pos[Body("R_Knee")]);
  // Our knee's local rotation is SMPL's conjugated by the y-up -> z-up map: SMPL's x axis is our
  // y axis (the body's left), so the shin turns by +1 rad about +y: toward -x, backward.
  const Vec3 shin_rest = Spec().body(Body("L_Ankle")).offset;
  const Vec3 expected = Quat(Eigen::AngleAxisd(1.0, Vec3::UnitY())) * shin_rest;
  EXPECT_LT((left_shin - expected).norm(), 1e-9) << left_shin.transpose() << " vs " << expected.transpose();
  EXPECT_LT(left_shin.x(), -0.25) << left_shin.transpose();  // heading frame: +x forward
  EXPECT_LT(left_shin.z(), -0.15) << left_shin.transpose();
  EXPECT_LT((right_shin - Spec().body(Body("R_Ankle")).offset).norm(), 1e-9) << right_shin.transpose();
  EXPECT_EQ(nb, Spec().num_bodies());
}

// ---------------------------------------------------------------------------------------------
// 3. Resampling.

TEST(MotionImportResample, SixtyToThirtyFps) {
  const std::string npz = TempPath("smpl.npz");
  AmassOptions options;
  WriteAmassNpz(npz, options);
  auto raw = ImportAmassNpz(npz, Spec());
  ASSERT_TRUE(raw.ok()) << raw.status();
  ImportOptions import;
  import.target_fps = 30.0;
  import.place_on_ground = false;
  auto clip = ImportMotionFile(npz, Spec(), import);
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_EQ(clip->num_frames, (options.frames - 1) / 2 + 1);
  EXPECT_EQ(clip->fps, 30.0);
  EXPECT_EQ(clip->body_pos.size(), static_cast<size_t>(clip->num_frames) * clip->num_bodies);
  // Frame k at 30 fps is source frame 2k at 60 fps.
  for (int f = 0; f < clip->num_frames; ++f) {
    EXPECT_LT((clip->root_pos[f] - raw->root_pos[2 * f]).norm(), 1e-9) << "frame " << f;
    for (int b = 0; b < clip->num_bodies; ++b) {
      EXPECT_LT(QuatDistance(clip->local(f, b), raw->local(2 * f, b)), 1e-7) << "frame " << f << " body " << b;
    }
  }
}

}  // namespace
}  // namespace modskill
