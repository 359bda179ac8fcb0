// Bad input to the motion importers: a non-OK status naming the file (and the field or row),
// never a crash.
#include "server/core/motion/motion_import.h"

#include "tests/motion_import_fixtures.h"

namespace modskill {
namespace {

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

}  // namespace
}  // namespace modskill
