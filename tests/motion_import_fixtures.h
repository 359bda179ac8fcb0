// What the motion importer tests share: the shipped source files, synthetic AMASS npz files
// (walk-like poses, or explicit root motion), and comparisons of clips.
#ifndef MODSKILL_TESTS_MOTION_IMPORT_FIXTURES_H_
#define MODSKILL_TESTS_MOTION_IMPORT_FIXTURES_H_

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
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/rotation_math.h"
#include "tests/npz_test_writer.h"
#include "tests/test_files.h"
#include "tests/test_fixtures.h"

namespace modskill {


using NpzWriter = ::modskill::testing::NpzWriter;
using ::testing::HasSubstr;

constexpr double kPi = 3.14159265358979323846;

inline const std::string kCmuBvh = std::string(MODSKILL_REPO_DIR) + "/data/motions/source/cmu/02_01.bvh";
inline const std::string kDeepMimicWalk =
    std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt";

inline std::string TempPath(const std::string& file_name) { return TestTempPath("motion_import_test", file_name); }

inline std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  EXPECT_TRUE(file.good()) << path;
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

inline const HumanoidSpec& Spec() { return DefaultSpec(); }

inline int Body(const std::string& name) {
  const int index = Spec().BodyIndex(name);
  EXPECT_GE(index, 0) << name;
  return index;
}

// Rotation angle between two orientations, insensitive to the quaternion double cover.
inline double QuatDistance(const Quat& a, const Quat& b) {
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
inline std::vector<double> AmassPoseRow(int f, double fps, int width) {
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

inline void WriteAmassNpz(const std::string& path, const AmassOptions& options) {
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
inline void WriteRootOnlyNpz(const std::string& path, const std::vector<Vec3>& root_axis_angle,
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

inline void ExpectSameMotion(const MotionClip& a, const MotionClip& b, double pos_tol, double rot_tol) {
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

inline void ExpectRoundTrip(const std::string& source_path, const std::string& clip_file_name) {
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

}  // namespace modskill

#endif  // MODSKILL_TESTS_MOTION_IMPORT_FIXTURES_H_
