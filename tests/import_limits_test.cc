// Issue 10, motion import side: every input that used to allocate without bound, cast an
// out-of-range double or name a path outside its directory gets a clear InvalidArgument naming
// the field. Each reproducer of the issue is one test; all run in well under a second each.
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/core/motion/clip_file.h"
#include "server/core/motion/clip_name.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/npz_reader.h"
#include "server/core/motion/resource_limits.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/util/confined_path.h"
#include "tests/npz_test_writer.h"
#include "tests/test_files.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using NpzWriter = ::modskill::testing::NpzWriter;
using ::testing::HasSubstr;

std::string TempPath(const std::string& file_name) { return TestTempPath("import_limits_test", file_name); }

const HumanoidSpec& Spec() { return DefaultSpec(); }

// Imports `bytes` written to a file named `file_name` and expects InvalidArgument mentioning
// every one of `fragments`.
void ExpectRejected(const std::string& file_name, const std::string& bytes, const std::vector<std::string>& fragments,
                    const ImportOptions& options = {}) {
  const std::string path = TempPath(file_name);
  WriteBytes(path, bytes);
  auto clip = ImportMotionFile(path, Spec(), options);
  ASSERT_FALSE(clip.ok()) << file_name << " was accepted";
  EXPECT_EQ(clip.status().code(), absl::StatusCode::kInvalidArgument) << clip.status();
  for (const std::string& fragment : fragments) EXPECT_THAT(std::string(clip.status().message()), HasSubstr(fragment));
}

// A one-joint BVH with two frames; the timing check comes before retargeting needs a skeleton.
std::string TinyBvh(const std::string& frame_time) {
  return absl::StrCat(
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation "
      "Xrotation\n  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\nFrames: 2\nFrame Time: ",
      frame_time, "\n0 90 0 0 0 0\n0 90 1 0 0 0\n");
}

// A DeepMimic clip of `frames` frames at rest, first frame duration `dt`.
std::string DeepMimicClip(double dt, int frames, double root_x = 0) {
  std::vector<std::string> rows;
  for (int f = 0; f < frames; ++f) {
    std::vector<double> v(44, 0.0);
    v[0] = dt;
    v[1] = root_x;
    v[2] = 0.9;
    for (int offset : {4, 8, 12, 16, 21, 25, 30, 35, 39}) v[offset] = 1.0;  // identity quaternions
    rows.push_back(absl::StrCat("[", absl::StrJoin(v, ","), "]"));
  }
  return absl::StrCat("{\"Loop\": \"none\", \"Frames\": [", absl::StrJoin(rows, ","), "]}");
}

// An AMASS-like npz: `frames` frames at rest, root translation `trans`.
std::string AmassNpz(int frames, double framerate, double trans = 0.0, bool compress = false) {
  NpzWriter writer;
  std::vector<float> poses(static_cast<size_t>(frames) * 72, 0.f);
  std::vector<float> t(static_cast<size_t>(frames) * 3, static_cast<float>(trans));
  writer.AddF32("poses", {frames, 72}, poses);
  writer.AddF32("trans", {frames, 3}, t);
  writer.AddF64("mocap_framerate", {}, {framerate});
  return writer.Serialize(compress);
}

// A native clip at rest with the given name, rate and root position (EncodeClip checks nothing).
std::string NativeClip(const std::string& name, double fps, double root_x = 0, int frames = 2) {
  MotionClip clip;
  clip.name = name;
  clip.fps = fps;
  clip.num_frames = frames;
  clip.num_bodies = Spec().num_bodies();
  clip.root_pos.assign(frames, Vec3(root_x, 0, 0.9));
  clip.local_rot.assign(static_cast<size_t>(frames) * clip.num_bodies, Quat::Identity());
  return EncodeClip(clip);
}

// ---------------------------------------------------------------------------------------------
// Defect 1: a tiny frame rate sized the resampled clip without bound.

TEST(TinyFrameRate, BvhFrameTime100000) { ExpectRejected("slow.bvh", TinyBvh("100000"), {"Frame Time", "max_clip_seconds"}); }

TEST(TinyFrameRate, BvhFrameTime1e9IsNotCastToGarbage) {
  ExpectRejected("slower.bvh", TinyBvh("1e9"), {"Frame Time", "max_clip_seconds"});
}

TEST(TinyFrameRate, DeepMimicDt1e5) { ExpectRejected("humanoid3d_slow.txt", DeepMimicClip(1e5, 2), {"dt", "max_clip_seconds"}); }

TEST(TinyFrameRate, NpzMocapFramerate1e5) {
  ExpectRejected("slow.npz", AmassNpz(2, 1e-5), {"mocap_framerate", "max_clip_seconds"});
}

TEST(TinyFrameRate, MsclipFps1e5) { ExpectRejected("slow.msclip", NativeClip("slow", 1e-5), {"fps", "max_clip_seconds"}); }

TEST(TinyFrameRate, MsclipFpsDenormal) {
  ExpectRejected("denormal.msclip", NativeClip("denormal", 5e-324), {"fps", "max_clip_seconds"});
}

TEST(TinyFrameRate, MsclipFpsNotFinite) {
  ExpectRejected("nan.msclip", NativeClip("nan", std::numeric_limits<double>::quiet_NaN()), {"fps"});
  ExpectRejected("inf.msclip", NativeClip("inf", std::numeric_limits<double>::infinity()), {"fps"});
}

TEST(TinyFrameRate, ResampleChecksTheOutputBeforeAllocating) {
  auto clip = DecodeClip(NativeClip("ok", 30.0), "ok");
  ASSERT_TRUE(clip.ok()) << clip.status();
  ResourceLimits limits;
  limits.max_clip_frames = 10;
  auto resampled = ResampleClip(*clip, 1000.0, limits);  // 1/30 s at 1000 fps: 34 frames
  ASSERT_FALSE(resampled.ok());
  EXPECT_THAT(std::string(resampled.status().message()), HasSubstr("max_clip_frames"));
  EXPECT_TRUE(ResampleClip(*clip, 60.0, limits).ok());
}

TEST(TinyFrameRate, ALongButLegalClipStillImports) {
  ImportOptions options;
  options.place_on_ground = false;
  const std::string path = TempPath("minute.bvh");
  WriteBytes(path, TinyBvh("60"));  // 2 frames one minute apart: 1801 frames at 30 fps
  auto clip = ImportMotionFile(path, Spec(), options);
  // The one-joint skeleton cannot be retargeted; what matters is that the timing passed.
  ASSERT_FALSE(clip.ok());
  EXPECT_THAT(std::string(clip.status().message()), ::testing::Not(HasSubstr("Frame Time")));
}

// ---------------------------------------------------------------------------------------------
// Defect 6: a compressed npz expanded without bound.

TEST(NpzBomb, ZeroFramesBeyondTheFrameLimit) {
  // The 117 KB archive: 200,000 frames of zeros, deflated.
  const std::string bytes = AmassNpz(200000, 30.0, 0.0, /*compress=*/true);
  EXPECT_LT(bytes.size(), size_t{1} << 20);
  // Refused at the frame count of the first matrix read, before it is converted to doubles.
  ExpectRejected("bomb.npz", bytes, {"bomb.npz", "200000 frames", "max_clip_frames"});
}

TEST(NpzBomb, RecordedSizesAreCheckedBeforeInflating) {
  const std::string path = TempPath("bomb.npz");
  WriteBytes(path, AmassNpz(20000, 30.0, 0.0, /*compress=*/true));  // 5.8 MB inflated
  ResourceLimits limits;
  limits.max_npz_member_bytes = 1 << 20;
  auto member = ReadNpz(path, limits);
  ASSERT_FALSE(member.ok());
  EXPECT_EQ(member.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(member.status().message()), HasSubstr("member 'poses.npy'"));
  EXPECT_THAT(std::string(member.status().message()), HasSubstr("max_npz_member_bytes"));
  limits = ResourceLimits();
  limits.max_decompressed_bytes = 4 << 20;
  auto total = ReadNpz(path, limits);
  ASSERT_FALSE(total.ok());
  EXPECT_THAT(std::string(total.status().message()), HasSubstr("max_decompressed_bytes"));
}

TEST(NpzBomb, ArraysAreBoundedAsDoubles) {
  // One byte per element on disk, eight in memory.
  const std::string npy = NpzWriter::MakeNpy("|u1", false, {4 << 20}, std::string(4 << 20, '\0'));
  ResourceLimits limits;
  limits.max_npz_member_bytes = 16 << 20;
  auto array = ParseNpy(npy, "big.npy", limits);
  ASSERT_FALSE(array.ok());
  EXPECT_THAT(std::string(array.status().message()), HasSubstr("max_npz_member_bytes"));
}

TEST(NpzBomb, ALyingSizeStopsAtTheRecordedSize) {
  // The central directory says 100 bytes; the member inflates to far more.
  std::string bytes = AmassNpz(1000, 30.0, 0.0, /*compress=*/true);
  const size_t directory = bytes.find("PK\x01\x02");
  ASSERT_NE(directory, std::string::npos);
  for (int k = 0; k < 4; ++k) bytes[directory + 24 + k] = "\x64\0\0\0"[k];
  const std::string path = TempPath("liar.npz");
  WriteBytes(path, bytes);
  auto archive = ReadNpz(path);
  ASSERT_FALSE(archive.ok());
  EXPECT_THAT(std::string(archive.status().message()), HasSubstr("inflates to more than the 100 bytes"));
}

// ---------------------------------------------------------------------------------------------
// Defect 7a: absurd positions.

TEST(AbsurdPosition, NpzRootAt1e30) {
  ExpectRejected("far.npz", AmassNpz(4, 30.0, 1e30), {"root_pos of frame 0", "max_position"});
}

TEST(AbsurdPosition, MsclipRootAt1e30) {
  ExpectRejected("far.msclip", NativeClip("far", 30.0, 1e30), {"clip 'far'", "root_pos of frame 0", "max_position"});
}

TEST(AbsurdPosition, DeepMimicRootAt1e30) {
  ExpectRejected("humanoid3d_far.txt", DeepMimicClip(1.0 / 30, 3, 1e30), {"root_pos of frame 0", "max_position"});
}

TEST(AbsurdPosition, ALongWalkWithinTheBoundIsFine) {
  const std::string path = TempPath("away.msclip");
  WriteBytes(path, NativeClip("away", 30.0, 9000.0));
  auto clip = ImportMotionFile(path, Spec());
  EXPECT_TRUE(clip.ok()) << clip.status();
}

// ---------------------------------------------------------------------------------------------
// Defect 2: path traversal through a clip's name.

TEST(ClipNames, Rules) {
  const int max = ResourceLimits().max_name_length;
  for (const char* good : {"cmu_02_01", "deepmimic_walk~R_Arm~12", "a-b.c", "x", "walk.v2~w~0"}) {
    EXPECT_TRUE(ValidateClipName(good, max).ok()) << good;
  }
  for (const std::string bad : {std::string(""), std::string("."), std::string(".."), std::string(".hidden"),
                                std::string("a..b"), std::string("a/b"), std::string("../../x/evil"),
                                std::string("a\\b"), std::string("a b"), std::string("a\nb"), std::string("a\0b", 3),
                                std::string("caf\xc3\xa9"), std::string(max + 1, 'a')}) {
    auto status = ValidateClipName(bad, max);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(status.message()), HasSubstr("name")) << bad;
  }
  EXPECT_TRUE(ValidateClipName(std::string(max, 'a'), max).ok());
}

TEST(ClipNames, DerivedNamesAreSanitized) {
  EXPECT_EQ(DefaultClipName("/tmp/my clip (1).npz"), "my_clip__1_");
  EXPECT_EQ(DefaultClipName("/tmp/..hidden.npz"), "hidden");
  EXPECT_EQ(DefaultClipName("/x/humanoid3d_walk.txt"), "deepmimic_walk");
  EXPECT_EQ(DefaultClipName("/x/02_01.bvh"), "cmu_02_01");
}

TEST(ClipNames, ImportRejectsATraversalName) {
  ImportOptions options;
  options.name = "../../x/evil";
  const std::string walk = std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt";
  auto clip = ImportMotionFile(walk, Spec(), options);
  ASSERT_FALSE(clip.ok());
  EXPECT_EQ(clip.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(clip.status().message()), HasSubstr("name '../../x/evil'"));
}

TEST(ClipNames, MsclipWithATraversalNameIsRejected) {
  ExpectRejected("stored.msclip", NativeClip("../../y", 30.0), {"name '../../y'"});
  ExpectRejected("long.msclip", NativeClip(std::string(1000, 'n'), 30.0), {"max", "1000 characters"});
}

TEST(ConfinedPaths, StayUnderTheDirectory) {
  const std::filesystem::path dir = std::filesystem::path(TempPath("out"));
  std::filesystem::create_directories(dir);
  auto ok = ConfinedPath(dir.string(), "walk.msclip");
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_EQ(std::filesystem::path(*ok).parent_path(), std::filesystem::canonical(dir));
  EXPECT_TRUE(ConfinedPath(dir.string() + "/", "walk~w~1.msclip").ok());
  for (const char* bad : {"../y.msclip", "../../x/evil~w~1.msclip", "a/b.msclip", "/etc/passwd", "..", ".", ""}) {
    auto path = ConfinedPath(dir.string(), bad);
    EXPECT_FALSE(path.ok()) << bad << " -> " << (path.ok() ? *path : "");
  }
  // A symbolic link inside the directory that points out of it is resolved and refused.
  const std::filesystem::path link = dir / "escape.msclip";
  std::filesystem::remove(link);
  std::filesystem::create_symlink("/tmp/modskill-escape.msclip", link);
  EXPECT_FALSE(ConfinedPath(dir.string(), "escape.msclip").ok());
}

}  // namespace
}  // namespace modskill
