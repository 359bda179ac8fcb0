// Tests of the motion importers (AMASS npz, CMU BVH, DeepMimic) and the native clip format:
// round trips, AMASS semantics, resampling, grounding, kinematic consistency and bad input.
#include "server/core/motion/motion_import.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/core/motion/bvh_parser.h"
#include "server/core/motion/clip_file.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/rotation_math.h"
#include "tests/npz_test_writer.h"
#include "tests/test_files.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using NpzWriter = ::modskill::testing::NpzWriter;
using ::testing::HasSubstr;

constexpr double kPi = 3.14159265358979323846;

const std::string kCmuBvh = std::string(MODSKILL_REPO_DIR) + "/data/motions/source/cmu/02_01.bvh";
const std::string kDeepMimicWalk =
    std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt";

std::string TempPath(const std::string& file_name) { return TestTempPath("motion_import_test", file_name); }

std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  EXPECT_TRUE(file.good()) << path;
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

const HumanoidSpec& Spec() { return DefaultSpec(); }

int Body(const std::string& name) {
  const int index = Spec().BodyIndex(name);
  EXPECT_GE(index, 0) << name;
  return index;
}

// Rotation angle between two orientations, insensitive to the quaternion double cover.
double QuatDistance(const Quat& a, const Quat& b) {
  const Quat d = a.conjugate() * b;
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

// ---------------------------------------------------------------------------------------------
// Synthetic AMASS files.

struct AmassOptions {
  int frames = 40;
  double fps = 60.0;
  bool smplh = false;  // N x 156 float64 with betas and gender, else N x 72 float32
  bool include_poses = true;
  bool include_trans = true;
  bool include_rate = true;
  int poses_width = 0;         // overrides the width (for bad shapes)
  int trans_rows = -1;         // overrides the row count of trans
  int nan_row = -1;            // puts a NaN into this row of poses
};

// Axis-angle of SMPL joint j in frame f: a smooth walk-like motion. The root rotates SMPL's
// y-up template upright in AMASS's z-up world (pi/2 about x) and sways a little in yaw.
std::vector<double> AmassPoseRow(int f, double fps, int width) {
  std::vector<double> row(width, 0.0);
  const double t = f / fps;
  const double phase = 2.0 * kPi * 1.2 * t;
  const Quat root = Quat(Eigen::AngleAxisd(0.2 * std::sin(0.5 * phase), Vec3::UnitZ())) *
                    Quat(Eigen::AngleAxisd(kPi / 2, Vec3::UnitX()));
  const Vec3 root_vector = RotationVector(root);
  for (int k = 0; k < 3; ++k) row[k] = root_vector[k];
  auto set = [&](int joint, double x, double y, double z) {
    row[3 * joint] = x;
    row[3 * joint + 1] = y;
    row[3 * joint + 2] = z;
  };
  set(1, -0.4 * std::sin(phase), 0.0, 0.05);           // L_Hip
  set(2, 0.4 * std::sin(phase), 0.0, -0.05);           // R_Hip
  set(4, 0.6 + 0.5 * std::sin(phase + 1.0), 0, 0);     // L_Knee
  set(5, 0.6 - 0.5 * std::sin(phase + 1.0), 0, 0);     // R_Knee
  set(16, 0.0, 0.0, -1.0 + 0.2 * std::sin(phase));     // L_Shoulder
  set(17, 0.0, 0.0, 1.0 + 0.2 * std::sin(phase));      // R_Shoulder
  set(18, 0.0, -0.3 - 0.2 * std::cos(phase), 0.0);     // L_Elbow
  set(19, 0.0, 0.3 + 0.2 * std::cos(phase), 0.0);      // R_Elbow
  if (width > 72) {
    // SMPL-H finger joints (after the 22 body joints): must not disturb the body.
    for (int k = 66; k < width; ++k) row[k] = 0.1 * std::sin(phase + k);
  }
  return row;
}

void WriteAmassNpz(const std::string& path, const AmassOptions& options) {
  const int n = options.frames;
  const int width = options.poses_width > 0 ? options.poses_width : (options.smplh ? 156 : 72);
  std::vector<double> poses;
  for (int f = 0; f < n; ++f) {
    std::vector<double> row = AmassPoseRow(f, options.fps, std::max(width, 72));
    row.resize(width);
    if (f == options.nan_row) row[3 * 4] = std::numeric_limits<double>::quiet_NaN();
    poses.insert(poses.end(), row.begin(), row.end());
  }
  const int trans_rows = options.trans_rows >= 0 ? options.trans_rows : n;
  std::vector<double> trans;
  for (int f = 0; f < trans_rows; ++f) {
    const double t = f / options.fps;
    // SMPL faces +z; the root's pi/2 about x turns that into world -y.
    trans.insert(trans.end(), {0.3, -1.2 * t, 0.95 + 0.02 * std::sin(2.0 * kPi * 2.4 * t)});
  }
  NpzWriter writer;
  if (options.include_trans) {
    if (options.smplh) {
      writer.AddF64("trans", {trans_rows, 3}, trans);
    } else {
      writer.AddF32("trans", {trans_rows, 3}, std::vector<float>(trans.begin(), trans.end()));
    }
  }
  if (options.smplh) {
    writer.AddString("gender", "female");
    writer.AddF64("betas", {16}, std::vector<double>(16, 0.0));
  }
  if (options.include_poses) {
    if (options.smplh) {
      writer.AddF64("poses", {n, width}, poses);
    } else {
      writer.AddF32("poses", {n, width}, std::vector<float>(poses.begin(), poses.end()));
    }
  }
  if (options.include_rate) writer.AddF64("mocap_framerate", {}, {options.fps});
  ASSERT_TRUE(writer.Write(path, /*compress=*/options.smplh)) << path;
}

// An npz with explicit per-frame root axis-angles and translations, everything else at rest.
void WriteRootOnlyNpz(const std::string& path, const std::vector<Vec3>& root_axis_angle,
                      const std::vector<Vec3>& trans, double fps) {
  const int n = static_cast<int>(root_axis_angle.size());
  std::vector<double> poses(static_cast<size_t>(n) * 72, 0.0), t;
  for (int f = 0; f < n; ++f) {
    for (int k = 0; k < 3; ++k) poses[72 * f + k] = root_axis_angle[f][k];
    t.insert(t.end(), {trans[f].x(), trans[f].y(), trans[f].z()});
  }
  NpzWriter writer;
  writer.AddF64("poses", {n, 72}, poses);
  writer.AddF64("trans", {n, 3}, t);
  writer.AddF64("mocap_framerate", {}, {fps});
  ASSERT_TRUE(writer.Write(path, /*compress=*/false)) << path;
}

// ---------------------------------------------------------------------------------------------
// Comparisons.

void ExpectSameMotion(const MotionClip& a, const MotionClip& b, double pos_tol, double rot_tol) {
  ASSERT_EQ(a.num_frames, b.num_frames);
  ASSERT_EQ(a.num_bodies, b.num_bodies);
  ASSERT_EQ(a.root_pos.size(), b.root_pos.size());
  ASSERT_EQ(a.local_rot.size(), b.local_rot.size());
  ASSERT_EQ(a.body_pos.size(), b.body_pos.size());
  ASSERT_EQ(a.body_pos.size(), static_cast<size_t>(a.num_frames) * a.num_bodies);
  double worst_root = 0, worst_local = 0, worst_body = 0;
  for (size_t i = 0; i < a.root_pos.size(); ++i) worst_root = std::max(worst_root, (a.root_pos[i] - b.root_pos[i]).norm());
  for (size_t i = 0; i < a.local_rot.size(); ++i) {
    worst_local = std::max(worst_local, QuatDistance(a.local_rot[i], b.local_rot[i]));
  }
  for (size_t i = 0; i < a.body_pos.size(); ++i) worst_body = std::max(worst_body, (a.body_pos[i] - b.body_pos[i]).norm());
  EXPECT_LT(worst_root, pos_tol) << "root_pos";
  EXPECT_LT(worst_local, rot_tol) << "local_rot";
  EXPECT_LT(worst_body, pos_tol) << "body_pos";
}

void ExpectRoundTrip(const std::string& source_path, const std::string& clip_file_name) {
  ImportOptions options;
  options.label = "a person walks forward";
  options.humanml3d_id = "012181";
  auto imported = ImportMotionFile(source_path, Spec(), options);
  ASSERT_TRUE(imported.ok()) << imported.status();
  ASSERT_GE(imported->num_frames, 2);
  EXPECT_EQ(imported->num_bodies, Spec().num_bodies());
  EXPECT_DOUBLE_EQ(imported->fps, 30.0);
  EXPECT_EQ(imported->source, std::filesystem::path(source_path).filename().string());
  EXPECT_EQ(imported->name, DefaultClipName(source_path));

  const std::string path = TempPath(clip_file_name);
  ASSERT_TRUE(WriteClipFile(path, *imported).ok());
  auto loaded = ReadClipFile(path, Spec());
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->name, imported->name);
  EXPECT_EQ(loaded->label, "a person walks forward");
  EXPECT_EQ(loaded->humanml3d_id, "012181");
  EXPECT_EQ(loaded->source, imported->source);
  EXPECT_EQ(loaded->fps, imported->fps);
  ExpectSameMotion(*imported, *loaded, 1e-5, 1e-5);

  // Through the generic entry point too: a native clip keeps its name and is not re-grounded.
  auto again = ImportMotionFile(path, Spec());
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->name, imported->name);
  ExpectSameMotion(*imported, *again, 1e-5, 1e-5);
}

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
// 6. Bad input: a non-OK status naming the file (and the field or row), never a crash.

void ExpectImportError(const std::string& path, std::initializer_list<std::string> needles) {
  auto clip = ImportMotionFile(path, Spec());
  ASSERT_FALSE(clip.ok()) << path << " imported";
  const std::string message(clip.status().message());
  EXPECT_THAT(message, HasSubstr(path));
  for (const std::string& needle : needles) EXPECT_THAT(message, HasSubstr(needle));
}

TEST(BadNpz, MissingPoses) {
  AmassOptions options;
  options.include_poses = false;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'poses'"});
}

TEST(BadNpz, MissingTrans) {
  AmassOptions options;
  options.include_trans = false;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'trans'"});
}

TEST(BadNpz, MissingFramerate) {
  AmassOptions options;
  options.include_rate = false;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'mocap_framerate'"});
}

TEST(BadNpz, PosesOfWrongWidth) {
  AmassOptions options;
  options.poses_width = 70;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'poses'"});
}

TEST(BadNpz, TransWithWrongRowCount) {
  AmassOptions options;
  options.trans_rows = options.frames - 1;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'trans'"});
}

TEST(BadNpz, NanInPoses) {
  AmassOptions options;
  options.nan_row = 17;
  const std::string path = TempPath("a.npz");
  WriteAmassNpz(path, options);
  ExpectImportError(path, {"'poses'", "row 17"});
}

TEST(BadNpz, TruncatedArchive) {
  const std::string good = TempPath("good.npz");
  WriteAmassNpz(good, {});
  ASSERT_TRUE(ImportMotionFile(good, Spec()).ok());
  const std::string bytes = ReadBytes(good);
  const std::string path = TempPath("truncated.npz");
  WriteBytes(path, bytes.substr(0, bytes.size() / 2));
  ExpectImportError(path, {});
}

TEST(BadNpz, ZeroByteFile) {
  const std::string path = TempPath("empty.npz");
  WriteBytes(path, "");
  ExpectImportError(path, {});
}

TEST(BadNpz, MissingFile) {
  const std::string path = TempPath("does_not_exist.npz");
  std::filesystem::remove(path);
  ExpectImportError(path, {});
}

// A 0-d string where the frame rate belongs (as a careless export writes str(fps)).
TEST(BadNpz, StringFramerate) {
  const std::string path = TempPath("a.npz");
  const int n = 4;
  NpzWriter writer;
  writer.AddF64("poses", {n, 72}, std::vector<double>(72 * n, 0.0));
  writer.AddF64("trans", {n, 3}, std::vector<double>(3 * n, 0.0));
  writer.AddString("mocap_framerate", "60");
  ASSERT_TRUE(writer.Write(path, false));
  ExpectImportError(path, {"'mocap_framerate'"});
}

// The same for a string-typed 'poses' of the right shape.
TEST(BadNpz, StringPoses) {
  const std::string path = TempPath("a.npz");
  const int n = 4;
  NpzWriter writer;
  std::string data;
  for (int i = 0; i < 72 * n; ++i) data += std::string("0\0\0\0", 4);  // '0' as UTF-32LE
  writer.AddRawMember("poses.npy", NpzWriter::MakeNpy("<U1", false, {n, 72}, data));
  writer.AddF64("trans", {n, 3}, std::vector<double>(3 * n, 0.0));
  writer.AddF64("mocap_framerate", {}, {60.0});
  ASSERT_TRUE(writer.Write(path, false));
  ExpectImportError(path, {"'poses'"});
}

TEST(BadBvh, TruncatedFile) {
  const std::string bytes = ReadBytes(kCmuBvh);
  ASSERT_GT(bytes.size(), 1000u);
  const std::string path = TempPath("truncated.bvh");
  WriteBytes(path, bytes.substr(0, bytes.size() * 6 / 10));
  ExpectImportError(path, {"frame"});
}

std::string SmallBvh(const std::vector<std::string>& leg_names) {
  // Root, spine, and two legs of three joints each (hip, knee, ankle), y-up, centimetres.
  std::string text = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
                     "  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
  auto leg = [&](const std::string& hip, const std::string& knee, const std::string& ankle, double side) {
    absl::StrAppend(&text, "  JOINT ", hip, "\n  {\n    OFFSET ", side * 9, " -5 0\n",
                    "    CHANNELS 3 Zrotation Yrotation Xrotation\n", "    JOINT ", knee,
                    "\n    {\n      OFFSET 0 -40 0\n      CHANNELS 3 Zrotation Yrotation Xrotation\n",
                    "      JOINT ", ankle,
                    "\n      {\n        OFFSET 0 -40 0\n        CHANNELS 3 Zrotation Yrotation Xrotation\n",
                    "        End Site\n        {\n          OFFSET 0 -5 10\n        }\n      }\n    }\n  }\n");
  };
  leg(leg_names[0], leg_names[1], leg_names[2], 1.0);
  leg(leg_names[3], leg_names[4], leg_names[5], -1.0);
  absl::StrAppend(&text, "  JOINT Spine\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Zrotation Yrotation Xrotation\n",
                  "    End Site\n    {\n      OFFSET 0 40 0\n    }\n  }\n}\n");
  const int channels = 6 + 7 * 3;
  absl::StrAppend(&text, "MOTION\nFrames: 3\nFrame Time: 0.0333333\n");
  for (int f = 0; f < 3; ++f) {
    std::vector<std::string> values(channels, "0");
    values[1] = "90";
    values[2] = absl::StrCat(f);
    absl::StrAppend(&text, absl::StrJoin(values, " "), "\n");
  }
  return text;
}

TEST(BadBvh, UnknownJointNames) {
  const std::string text = SmallBvh({"HipL", "KneeL", "AnkleL", "HipR", "KneeR", "AnkleR"});
  // The file itself is a valid BVH: the error must come from the joint names.
  auto parsed = ParseBvh(text, "small.bvh");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  EXPECT_EQ(parsed->num_joints(), 8);
  const std::string path = TempPath("unknown_names.bvh");
  WriteBytes(path, text);
  ExpectImportError(path, {"unknown joint name"});
}

// ---- DeepMimic.

// One humanoid3d frame of 44 numbers: dt, root position, then rotations at rest.
std::vector<std::string> DeepMimicFrame(double x) {
  std::vector<std::string> v = {"0.0333333333333", absl::StrCat(x), "0.85", "0"};
  // root, chest, neck, right hip quaternions; right knee; right ankle, right shoulder;
  // right elbow; left hip; left knee; left ankle, left shoulder; left elbow.
  const char* layout[] = {"q", "q", "q", "q", "a", "q", "q", "a", "q", "a", "q", "q", "a"};
  for (const char* kind : layout) {
    if (std::string(kind) == "q") {
      v.insert(v.end(), {"1", "0", "0", "0"});
    } else {
      v.push_back("0");
    }
  }
  return v;
}

std::string DeepMimicText(const std::vector<std::vector<std::string>>& frames) {
  std::vector<std::string> rows;
  for (const auto& frame : frames) rows.push_back(absl::StrCat("[", absl::StrJoin(frame, ", "), "]"));
  return absl::StrCat("{\n\"Loop\": \"wrap\",\n\"Frames\": [\n", absl::StrJoin(rows, ",\n"), "\n]\n}\n");
}

TEST(BadDeepMimic, SyntheticFramesAreValid) {
  ASSERT_EQ(DeepMimicFrame(0).size(), 44u);
  const std::string path = TempPath("humanoid3d_ok.txt");
  WriteBytes(path, DeepMimicText({DeepMimicFrame(0), DeepMimicFrame(0.05), DeepMimicFrame(0.1)}));
  auto clip = ImportMotionFile(path, Spec());
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_EQ(clip->num_frames, 3);
}

TEST(BadDeepMimic, NotJson) {
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, "Frames: [[0.0333, 0, 0.85");
  ExpectImportError(path, {"JSON"});
}

TEST(BadDeepMimic, NoFrames) {
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, "{\"Loop\": \"wrap\", \"frames\": []}");
  ExpectImportError(path, {"Frames"});
}

TEST(BadDeepMimic, FrameWith43Numbers) {
  std::vector<std::string> short_frame = DeepMimicFrame(0.05);
  short_frame.pop_back();
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, DeepMimicText({DeepMimicFrame(0), DeepMimicFrame(0.05), short_frame}));
  ExpectImportError(path, {"Frames[2]"});
}

TEST(BadDeepMimic, StringElement) {
  std::vector<std::string> bad = DeepMimicFrame(0.05);
  bad[10] = "\"x\"";
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, DeepMimicText({DeepMimicFrame(0), bad, DeepMimicFrame(0.1)}));
  ExpectImportError(path, {"Frames[1][10]"});
}

TEST(BadDeepMimic, HugeNumber) {
  std::vector<std::string> bad = DeepMimicFrame(0.05);
  bad[1] = "1e999";
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, DeepMimicText({DeepMimicFrame(0), bad, DeepMimicFrame(0.1)}));
  ExpectImportError(path, {});
}

TEST(BadDeepMimic, OnlyOneFrame) {
  const std::string path = TempPath("humanoid3d_bad.txt");
  WriteBytes(path, DeepMimicText({DeepMimicFrame(0)}));
  ExpectImportError(path, {"Frames"});
}

// ---- Native .msclip.

class BadClipFile : public ::testing::Test {
 protected:
  void SetUp() override {
    auto clip = ImportMotionFile(kDeepMimicWalk, Spec());
    ASSERT_TRUE(clip.ok()) << clip.status();
    clip_ = *std::move(clip);
    bytes_ = EncodeClip(clip_);
    // The bytes as encoded decode: the failures below come from the damage.
    auto decoded = DecodeClip(bytes_, "walk.msclip");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    ASSERT_GT(bytes_.size(), 200u);
  }

  void ExpectRejected(const std::string& bytes, const std::string& needle) {
    auto decoded = DecodeClip(bytes, "damaged.msclip");
    ASSERT_FALSE(decoded.ok());
    EXPECT_THAT(std::string(decoded.status().message()), HasSubstr("damaged.msclip"));
    EXPECT_THAT(std::string(decoded.status().message()), HasSubstr(needle));
    const std::string path = TempPath("damaged.msclip");
    WriteBytes(path, bytes);
    auto read = ReadClipFile(path, Spec());
    ASSERT_FALSE(read.ok());
    EXPECT_THAT(std::string(read.status().message()), HasSubstr(path));
    EXPECT_THAT(std::string(read.status().message()), HasSubstr(needle));
    ExpectImportError(path, {needle});
  }

  MotionClip clip_;
  std::string bytes_;
};

TEST_F(BadClipFile, CorruptByte) {
  std::string bytes = bytes_;
  bytes[bytes.size() / 2] ^= 0x5A;
  ExpectRejected(bytes, "checksum");
}

TEST_F(BadClipFile, Truncated) {
  ExpectRejected(bytes_.substr(0, bytes_.size() / 2), "checksum");
  ExpectRejected(bytes_.substr(0, 10), "magic");
}

TEST_F(BadClipFile, WrongMagic) {
  std::string bytes = bytes_;
  bytes[0] = 'X';
  ExpectRejected(bytes, "magic");
}

TEST_F(BadClipFile, NanRootPosition) {
  MotionClip bad = clip_;
  bad.root_pos[3].x() = std::numeric_limits<double>::quiet_NaN();
  // WriteClipFile validates, so nothing is written ...
  const std::string refused = TempPath("refused.msclip");
  std::filesystem::remove(refused);
  EXPECT_FALSE(WriteClipFile(refused, bad).ok());
  EXPECT_FALSE(std::filesystem::exists(refused));
  // ... but the bytes of such a clip, checksum intact, must still be rejected on reading.
  ExpectRejected(EncodeClip(bad), "root_pos of frame 3");
}

TEST(BadFile, UnknownExtension) {
  const std::string path = TempPath("motion.xyz");
  WriteBytes(path, "whatever");
  ExpectImportError(path, {"'.xyz'"});
}

TEST(BadFile, MissingBvhAndClip) {
  for (const char* name : {"missing.bvh", "missing.msclip", "humanoid3d_missing.txt"}) {
    const std::string path = TempPath(name);
    std::filesystem::remove(path);
    ExpectImportError(path, {});
  }
}

TEST(BadFile, NonPositiveTargetFps) {
  ImportOptions options;
  options.target_fps = 0;
  EXPECT_FALSE(ImportMotionFile(kDeepMimicWalk, Spec(), options).ok());
}

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

}  // namespace
}  // namespace modskill
