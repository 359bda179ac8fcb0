#include "server/core/motion/bvh_parser.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"

// tests/CMakeLists.txt is expected to define this; the fallback keeps a hand build working.
#ifndef MODSKILL_REPO_DIR
#define MODSKILL_REPO_DIR "/work/main"
#endif

namespace modskill {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Line numbers matter: the error tests below name them.
constexpr char kSmallBvh[] =
    "HIERARCHY\n"                                                                 // 1
    "ROOT Hips\n"                                                                 // 2
    "{\n"                                                                         // 3
    "  OFFSET 1 2 3\n"                                                            // 4
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"  // 5
    "  JOINT Spine\n"                                                             // 6
    "  {\n"                                                                       // 7
    "    OFFSET 0 5 0\n"                                                          // 8
    "    CHANNELS 3 Zrotation Xrotation Yrotation\n"                              // 9
    "    JOINT Head\n"                                                            // 10
    "    {\n"                                                                     // 11
    "      OFFSET 0 4 0.5\n"                                                      // 12
    "      CHANNELS 3 Xrotation Yrotation Zrotation\n"                            // 13
    "      End Site\n"                                                            // 14
    "      {\n"                                                                   // 15
    "        OFFSET 0 2 0\n"                                                      // 16
    "      }\n"                                                                   // 17
    "    }\n"                                                                     // 18
    "  }\n"                                                                       // 19
    "}\n"                                                                         // 20
    "MOTION\n"                                                                    // 21
    "Frames: 2\n"                                                                 // 22
    "Frame Time: .0083333\n"                                                      // 23
    "10 20 30 90 0 90 0 0 0 0 0 0\n"                                              // 24
    "-1.5e-3 .5 7 0 45 0 90 90 0 10 20 30\n";                                     // 25

Eigen::Quaterniond Rx(double degrees) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDeg, Eigen::Vector3d::UnitX()));
}
Eigen::Quaterniond Ry(double degrees) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDeg, Eigen::Vector3d::UnitY()));
}
Eigen::Quaterniond Rz(double degrees) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDeg, Eigen::Vector3d::UnitZ()));
}

// Same rotation, either sign of the quaternion.
void ExpectSameRotation(const Eigen::Quaterniond& actual, const Eigen::Quaterniond& expected) {
  EXPECT_LT(actual.angularDistance(expected), 1e-9)
      << "actual " << actual.coeffs().transpose() << " expected " << expected.coeffs().transpose();
}

std::string Replace(absl::string_view text, absl::string_view from, absl::string_view to) {
  EXPECT_TRUE(absl::StrContains(text, from)) << from;
  return absl::StrReplaceAll(text, {{from, to}});
}

// Parses text that must fail; returns the message, which must start with the file name.
std::string ParseError(absl::string_view text) {
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "test.bvh");
  EXPECT_FALSE(clip.ok());
  if (clip.ok()) return "";
  EXPECT_THAT(std::string(clip.status().message()), StartsWith("test.bvh:"));
  return std::string(clip.status().message());
}

void ExpectSmallClip(const BvhClip& clip) {
  ASSERT_EQ(clip.num_joints(), 3);
  EXPECT_EQ(clip.joints[0].name, "Hips");
  EXPECT_EQ(clip.joints[1].name, "Spine");
  EXPECT_EQ(clip.joints[2].name, "Head");
  EXPECT_EQ(clip.joints[0].parent, -1);
  EXPECT_EQ(clip.joints[1].parent, 0);
  EXPECT_EQ(clip.joints[2].parent, 1);
  EXPECT_EQ(clip.JointIndex("Head"), 2);
  EXPECT_EQ(clip.JointIndex("Tail"), -1);

  EXPECT_TRUE(clip.joints[0].offset.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(clip.joints[1].offset.isApprox(Eigen::Vector3d(0, 5, 0)));
  EXPECT_TRUE(clip.joints[2].offset.isApprox(Eigen::Vector3d(0, 4, 0.5)));
  EXPECT_FALSE(clip.joints[0].has_end_site);
  EXPECT_FALSE(clip.joints[1].has_end_site);
  EXPECT_TRUE(clip.joints[2].has_end_site);
  EXPECT_TRUE(clip.joints[2].end_site_offset.isApprox(Eigen::Vector3d(0, 2, 0)));
  EXPECT_EQ(clip.joints[0].channels,
            (std::vector<std::string>{"Xposition", "Yposition", "Zposition", "Zrotation",
                                      "Yrotation", "Xrotation"}));
  EXPECT_EQ(clip.joints[1].channels,
            (std::vector<std::string>{"Zrotation", "Xrotation", "Yrotation"}));

  EXPECT_EQ(clip.num_frames, 2);
  EXPECT_DOUBLE_EQ(clip.frame_time, 0.0083333);
  ASSERT_EQ(clip.root_translation.size(), 2u);
  ASSERT_EQ(clip.local_rotation.size(), 6u);
  EXPECT_TRUE(clip.root_translation[0].isApprox(Eigen::Vector3d(10, 20, 30)));
  EXPECT_NEAR(clip.root_translation[1].x(), -1.5e-3, 1e-15);
  EXPECT_NEAR(clip.root_translation[1].y(), 0.5, 1e-15);
  EXPECT_NEAR(clip.root_translation[1].z(), 7, 1e-15);

  // Frame 0: "Zrotation 90, Yrotation 0, Xrotation 90" is Rz * Rx.
  ExpectSameRotation(clip.LocalRotation(0, 0), Rz(90) * Rx(90));
  ExpectSameRotation(clip.LocalRotation(0, 1), Eigen::Quaterniond::Identity());
  ExpectSameRotation(clip.LocalRotation(0, 2), Eigen::Quaterniond::Identity());
  // Rx first takes +y to +z, then Rz leaves +z alone; the reverse order would give +x.
  EXPECT_TRUE((clip.LocalRotation(0, 0) * Eigen::Vector3d::UnitY())
                  .isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  // Frame 1.
  ExpectSameRotation(clip.LocalRotation(1, 0), Ry(45));
  ExpectSameRotation(clip.LocalRotation(1, 1), Rz(90) * Rx(90) * Ry(0));
  ExpectSameRotation(clip.LocalRotation(1, 2), Rx(10) * Ry(20) * Rz(30));
  EXPECT_GT(clip.LocalRotation(1, 2).angularDistance(Rz(30) * Ry(20) * Rx(10)), 1e-3);
}

TEST(BvhParserTest, ParsesSmallClip) {
  absl::StatusOr<BvhClip> clip = ParseBvh(kSmallBvh, "small.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  ExpectSmallClip(*clip);
}

TEST(BvhParserTest, ToleratesWindowsLineEndingsTabsAndBlankLines) {
  std::string text = absl::StrReplaceAll(kSmallBvh, {{"\n", " \t\r\n\t"}, {"  ", "\t"}});
  text = absl::StrCat("\r\n  \t", Replace(text, "MOTION", "\r\n\r\nMOTION\t"), "\r\n\r\n  ");
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "windows.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  ExpectSmallClip(*clip);
}

TEST(BvhParserTest, AcceptsBracesOnNameLinesAndCompactHeaders) {
  std::string text = Replace(kSmallBvh, "ROOT Hips\n{", "ROOT Hips {");
  text = Replace(text, "End Site\n      {", "End Site {");
  text = Replace(text, "Frames: 2", "Frames:2");
  text = Replace(text, "Frame Time: .0083333", "Frame  Time:\t8.3333e-3");
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "compact.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  ExpectSmallClip(*clip);
}

TEST(BvhParserTest, RootWithoutPositionChannelsUsesOffset) {
  std::string text =
      Replace(kSmallBvh, "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
              "CHANNELS 3 Zrotation Yrotation Xrotation");
  text = Replace(text, "10 20 30 90 0 90", "90 0 90");
  text = Replace(text, "-1.5e-3 .5 7 0 45 0", "0 45 0");
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "no_position.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_TRUE(clip->root_translation[0].isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(clip->root_translation[1].isApprox(Eigen::Vector3d(1, 2, 3)));
  ExpectSameRotation(clip->LocalRotation(0, 0), Rz(90) * Rx(90));
  ExpectSameRotation(clip->LocalRotation(1, 0), Ry(45));
}

TEST(BvhParserTest, NonRootPositionChannelsAreCountedButIgnored) {
  std::string text = Replace(kSmallBvh, "CHANNELS 3 Zrotation Xrotation Yrotation",
                             "CHANNELS 6 Zrotation Xposition Xrotation Yposition Yrotation "
                             "Zposition");
  text = Replace(text, "10 20 30 90 0 90 0 0 0 0 0 0", "10 20 30 90 0 90 0 5 0 6 0 7 0 0 0");
  text = Replace(text, "-1.5e-3 .5 7 0 45 0 90 90 0 10 20 30",
                 "-1.5e-3 .5 7 0 45 0 90 5 90 6 0 7 10 20 30");
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "mixed.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_EQ(clip->joints[1].channels.size(), 6u);
  EXPECT_TRUE(clip->root_translation[0].isApprox(Eigen::Vector3d(10, 20, 30)));
  ExpectSameRotation(clip->LocalRotation(0, 1), Eigen::Quaterniond::Identity());
  ExpectSameRotation(clip->LocalRotation(1, 1), Rz(90) * Rx(90));
  ExpectSameRotation(clip->LocalRotation(1, 2), Rx(10) * Ry(20) * Rz(30));
}

TEST(BvhParserTest, ZeroFramesIsValid) {
  std::string text = Replace(kSmallBvh, "Frames: 2", "Frames: 0");
  text = text.substr(0, text.find("10 20 30"));
  absl::StatusOr<BvhClip> clip = ParseBvh(text, "empty_motion.bvh");
  ASSERT_TRUE(clip.ok()) << clip.status();
  EXPECT_EQ(clip->num_frames, 0);
  EXPECT_TRUE(clip->local_rotation.empty());
}

TEST(BvhParserTest, ParsesCmuClip) {
  const std::string path = MODSKILL_REPO_DIR "/data/motions/source/cmu/02_01.bvh";
  absl::StatusOr<BvhClip> clip = ReadBvhFile(path);
  ASSERT_TRUE(clip.ok()) << clip.status();
  ASSERT_EQ(clip->num_joints(), 31);
  EXPECT_EQ(clip->num_frames, 344);
  EXPECT_DOUBLE_EQ(clip->frame_time, 0.0083333);
  EXPECT_EQ(clip->joints[0].name, "Hips");
  EXPECT_EQ(clip->joints[1].name, "LHipJoint");
  const int left_up_leg = clip->JointIndex("LeftUpLeg");
  ASSERT_GE(left_up_leg, 0);
  EXPECT_EQ(clip->joints[left_up_leg].parent, clip->JointIndex("LHipJoint"));
  EXPECT_TRUE(
      clip->joints[left_up_leg].offset.isApprox(Eigen::Vector3d(1.65674, -1.80282, 0.62477)));
  for (int j = 1; j < clip->num_joints(); ++j) {
    EXPECT_LT(clip->joints[j].parent, j) << clip->joints[j].name;
  }
  ASSERT_EQ(clip->root_translation.size(), 344u);
  ASSERT_EQ(clip->local_rotation.size(), 344u * 31u);
  for (const Eigen::Quaterniond& q : clip->local_rotation) {
    ASSERT_NEAR(q.norm(), 1.0, 1e-12);
  }
  // First frame: "10.4194 16.7048 -30.1003 0 0 0 | 0 0 0 | -21 0 0 ...".
  EXPECT_TRUE(clip->root_translation[0].isApprox(Eigen::Vector3d(10.4194, 16.7048, -30.1003)));
  ExpectSameRotation(clip->LocalRotation(0, left_up_leg), Rz(-21));
}

TEST(BvhParserTest, ReadBvhFileReportsMissingFile) {
  absl::StatusOr<BvhClip> clip = ReadBvhFile("/nonexistent/dir/clip.bvh");
  ASSERT_FALSE(clip.ok());
  EXPECT_THAT(std::string(clip.status().message()), HasSubstr("/nonexistent/dir/clip.bvh"));
}

// ---- One test per failure; each names the line (or frame index) of the problem. ----

TEST(BvhParserErrorTest, MissingHierarchy) {
  const std::string text = Replace(kSmallBvh, "HIERARCHY\n", "\n");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":2:"), HasSubstr("HIERARCHY")));
  EXPECT_THAT(ParseError(""), AllOf(HasSubstr(":1:"), HasSubstr("HIERARCHY")));
}

TEST(BvhParserErrorTest, MissingMotion) {
  const std::string text = std::string(kSmallBvh).substr(0, std::string(kSmallBvh).find("MOTION"));
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":20:"), HasSubstr("MOTION")));
}

TEST(BvhParserErrorTest, UnclosedBrace) {
  // The End Site's "}" on line 17 is blanked: every block closes one line late.
  const std::string text = Replace(kSmallBvh, "      }\n    }\n", "\n    }\n");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":21:"), HasSubstr("unbalanced braces"), HasSubstr("Hips")));
}

TEST(BvhParserErrorTest, UnclosedBraceAtEndOfFile) {
  const std::string text = "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n";
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":4:"), HasSubstr("unbalanced braces")));
}

TEST(BvhParserErrorTest, ExtraClosingBrace) {
  const std::string text = Replace(kSmallBvh, "}\nMOTION", "}\n}\nMOTION");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":21:"), HasSubstr("unbalanced braces")));
}

TEST(BvhParserErrorTest, UnknownChannelName) {
  const std::string text = Replace(kSmallBvh, "CHANNELS 3 Zrotation Xrotation Yrotation",
                                   "CHANNELS 3 Zrotation "
                                   "Wrotation Yrotation");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":9:"), HasSubstr("unknown channel name"), HasSubstr("Wrotation")));
}

TEST(BvhParserErrorTest, ChannelsCountMismatch) {
  const std::string fewer = Replace(kSmallBvh, "CHANNELS 3 Zrotation Xrotation Yrotation",
                                    "CHANNELS 3 Zrotation Xrotation");
  EXPECT_THAT(ParseError(fewer), AllOf(HasSubstr(":9:"), HasSubstr("mismatch")));
  const std::string more = Replace(kSmallBvh, "CHANNELS 3 Xrotation Yrotation Zrotation",
                                   "CHANNELS 2 Xrotation Yrotation Zrotation");
  EXPECT_THAT(ParseError(more), AllOf(HasSubstr(":13:"), HasSubstr("mismatch")));
  const std::string too_many = Replace(kSmallBvh, "CHANNELS 3 Xrotation Yrotation Zrotation",
                                       "CHANNELS 7 Xrotation Yrotation Zrotation");
  EXPECT_THAT(ParseError(too_many), HasSubstr(":13:"));
  const std::string twice = Replace(kSmallBvh, "CHANNELS 3 Xrotation Yrotation Zrotation",
                                    "CHANNELS 3 Xrotation Yrotation Xrotation");
  EXPECT_THAT(ParseError(twice), AllOf(HasSubstr(":13:"), HasSubstr("twice")));
}

TEST(BvhParserErrorTest, FramesMissing) {
  const std::string text = Replace(kSmallBvh, "Frames: 2\n", "\n");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":23:"), HasSubstr("Frames:")));
  const std::string not_integer = Replace(kSmallBvh, "Frames: 2", "Frames: two");
  EXPECT_THAT(ParseError(not_integer), AllOf(HasSubstr(":22:"), HasSubstr("two")));
}

TEST(BvhParserErrorTest, FramesNegative) {
  const std::string text = Replace(kSmallBvh, "Frames: 2", "Frames: -1");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":22:"), HasSubstr("negative")));
}

TEST(BvhParserErrorTest, FrameTimeNotPositive) {
  const std::string zero = Replace(kSmallBvh, "Frame Time: .0083333", "Frame Time: 0");
  EXPECT_THAT(ParseError(zero), AllOf(HasSubstr(":23:"), HasSubstr("Frame Time")));
  const std::string negative = Replace(kSmallBvh, "Frame Time: .0083333", "Frame Time: -0.01");
  EXPECT_THAT(ParseError(negative), AllOf(HasSubstr(":23:"), HasSubstr("Frame Time")));
}

TEST(BvhParserErrorTest, FrameTimeMissing) {
  const std::string text = Replace(kSmallBvh, "Frame Time: .0083333\n", "\n");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":24:"), HasSubstr("Frame Time")));
}

TEST(BvhParserErrorTest, FrameWithTooFewValues) {
  const std::string text = Replace(kSmallBvh, "90 90 0 10 20 30", "90 90 0 10 20");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":25:"), HasSubstr("frame index 1"), HasSubstr("too few")));
}

TEST(BvhParserErrorTest, FrameWithTooManyValues) {
  const std::string text =
      Replace(kSmallBvh, "10 20 30 90 0 90 0 0 0 0 0 0", "10 20 30 90 0 90 0 0 0 0 0 0 0");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":24:"), HasSubstr("frame index 0"), HasSubstr("too many")));
}

TEST(BvhParserErrorTest, NonNumericTokens) {
  const std::string in_frame = Replace(kSmallBvh, "90 90 0 10 20 30", "90 90 0 10 abc 30");
  EXPECT_THAT(ParseError(in_frame), AllOf(HasSubstr(":25:"), HasSubstr("frame index 1"),
                                          HasSubstr("abc"), HasSubstr("not a number")));
  const std::string in_offset = Replace(kSmallBvh, "OFFSET 0 5 0", "OFFSET 0 5x 0");
  EXPECT_THAT(ParseError(in_offset), AllOf(HasSubstr(":8:"), HasSubstr("not a number")));
  const std::string short_offset = Replace(kSmallBvh, "OFFSET 0 5 0", "OFFSET 0 5");
  EXPECT_THAT(ParseError(short_offset), AllOf(HasSubstr(":8:"), HasSubstr("OFFSET")));
  const std::string in_frame_time = Replace(kSmallBvh, "Frame Time: .0083333", "Frame Time: x");
  EXPECT_THAT(ParseError(in_frame_time), AllOf(HasSubstr(":23:"), HasSubstr("not a number")));
}

TEST(BvhParserErrorTest, NanAndInfValues) {
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "1e999"}) {
    const std::string in_frame =
        Replace(kSmallBvh, "90 90 0 10 20 30", absl::StrCat("90 90 0 10 ", bad, " 30"));
    EXPECT_THAT(ParseError(in_frame),
                AllOf(HasSubstr(":25:"), HasSubstr("frame index 1"), HasSubstr("NaN or infinite")))
        << bad;
  }
  const std::string in_offset = Replace(kSmallBvh, "OFFSET 0 5 0", "OFFSET 0 nan 0");
  EXPECT_THAT(ParseError(in_offset), AllOf(HasSubstr(":8:"), HasSubstr("NaN or infinite")));
  const std::string in_frame_time = Replace(kSmallBvh, "Frame Time: .0083333", "Frame Time: inf");
  EXPECT_THAT(ParseError(in_frame_time), AllOf(HasSubstr(":23:"), HasSubstr("NaN")));
}

TEST(BvhParserErrorTest, TruncatedFrames) {
  const std::string text = Replace(kSmallBvh, "Frames: 2", "Frames: 3");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":25:"), HasSubstr("truncated"), HasSubstr("frame index 2")));
  // A huge Frames: count must not allocate up front.
  const std::string huge = Replace(kSmallBvh, "Frames: 2", "Frames: 2000000000");
  EXPECT_THAT(ParseError(huge), HasSubstr("truncated"));
}

TEST(BvhParserErrorTest, MoreFrameLinesThanFrames) {
  const std::string text = Replace(kSmallBvh, "Frames: 2", "Frames: 1");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":25:"), HasSubstr("Frames")));
}

TEST(BvhParserErrorTest, MissingOffset) {
  const std::string text = Replace(kSmallBvh, "    OFFSET 0 5 0\n", "\n");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":6:"), HasSubstr("no OFFSET")));
}

TEST(BvhParserErrorTest, MoreThanOneRoot) {
  const std::string text = Replace(kSmallBvh, "}\nMOTION", "}\nROOT Other\nMOTION");
  EXPECT_THAT(ParseError(text), AllOf(HasSubstr(":21:"), HasSubstr("ROOT")));
}

TEST(BvhParserErrorTest, DuplicateJointNames) {
  const std::string text = Replace(kSmallBvh, "JOINT Head", "JOINT Spine");
  EXPECT_THAT(ParseError(text),
              AllOf(HasSubstr(":10:"), HasSubstr("duplicate"), HasSubstr("line 6")));
}

// A chain Joint0 -> Joint1 -> ...; joint i's keyword sits on line 2 + 4 * i.
std::string ChainBvh(int num_joints) {
  std::string text = "HIERARCHY\n";
  for (int i = 0; i < num_joints; ++i) {
    absl::StrAppend(&text, i == 0 ? "ROOT" : "JOINT", " Joint", i, "\n{\nOFFSET 0 0 1\n",
                    "CHANNELS 3 Zrotation Yrotation Xrotation\n");
  }
  for (int i = 0; i < num_joints; ++i) text += "}\n";
  text += "MOTION\nFrames: 1\nFrame Time: 0.1\n";
  for (int i = 0; i < num_joints; ++i) text += "0 0 0 ";
  return text + "\n";
}

TEST(BvhParserErrorTest, TooManyJoints) {
  absl::StatusOr<BvhClip> limit = ParseBvh(ChainBvh(kMaxBvhJoints), "chain.bvh");
  ASSERT_TRUE(limit.ok()) << limit.status();
  EXPECT_EQ(limit->num_joints(), kMaxBvhJoints);
  EXPECT_THAT(ParseError(ChainBvh(kMaxBvhJoints + 1)),
              AllOf(HasSubstr(absl::StrCat(":", 2 + 4 * kMaxBvhJoints, ":")),
                    HasSubstr("more than 1000 joints")));
}

TEST(BvhParserErrorTest, TextTooLarge) {
  // Reserved but never touched address space: the size check must come before any reading.
  const size_t size = static_cast<size_t>(kMaxBvhFileBytes) + 1;
  void* memory = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  ASSERT_NE(memory, MAP_FAILED);
  absl::StatusOr<BvhClip> clip =
      ParseBvh(absl::string_view(static_cast<const char*>(memory), size), "huge.bvh");
  munmap(memory, size);
  ASSERT_FALSE(clip.ok());
  EXPECT_THAT(std::string(clip.status().message()),
              AllOf(StartsWith("huge.bvh:"), HasSubstr("too large")));
}

TEST(BvhParserErrorTest, FileTooLarge) {
  // A sparse file: large on paper, no disk blocks.
  const std::string path = absl::StrCat(::testing::TempDir(), "/bvh_parser_test_huge.bvh");
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fclose(file);
  ASSERT_EQ(truncate(path.c_str(), kMaxBvhFileBytes + 1), 0);
  absl::StatusOr<BvhClip> clip = ReadBvhFile(path);
  std::remove(path.c_str());
  ASSERT_FALSE(clip.ok());
  EXPECT_THAT(std::string(clip.status().message()), AllOf(HasSubstr(path), HasSubstr("too large")));
}

// No prefix or corruption of a valid file may crash; failures still name the file.
TEST(BvhParserErrorTest, PrefixesAndCorruptionsFailCleanly) {
  const std::string valid = kSmallBvh;
  for (size_t length = 0; length < valid.size(); ++length) {
    absl::StatusOr<BvhClip> clip = ParseBvh(valid.substr(0, length), "prefix.bvh");
    if (!clip.ok()) {
      EXPECT_THAT(std::string(clip.status().message()), StartsWith("prefix.bvh:")) << length;
    }
  }
  std::mt19937 random(7);
  const std::string replacements = "{} \n\r\t0-.eX:#";
  for (int trial = 0; trial < 2000; ++trial) {
    std::string corrupted = valid;
    for (int edit = 0; edit < 3; ++edit) {
      corrupted[random() % corrupted.size()] = replacements[random() % replacements.size()];
    }
    absl::StatusOr<BvhClip> clip = ParseBvh(corrupted, "corrupt.bvh");
    if (clip.ok()) {
      EXPECT_EQ(clip->local_rotation.size(), clip->joints.size() * clip->num_frames);
    } else {
      EXPECT_THAT(std::string(clip.status().message()), StartsWith("corrupt.bvh:"));
    }
  }
}

}  // namespace
}  // namespace modskill
