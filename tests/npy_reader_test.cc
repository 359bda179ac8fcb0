// The .npy format: ParseNpy on its own (dtypes, byte orders, Fortran order, format versions),
// and broken .npy members inside an archive, whose messages name the file and the member.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "server/core/motion/npy_reader.h"
#include "server/core/motion/npz_reader.h"
#include "tests/npz_test_helpers.h"
#include "tests/npz_test_writer.h"
#include "tests/test_files.h"

namespace modskill {
namespace {

using NpzWriter = ::modskill::testing::NpzWriter;
using ::modskill::testing::ExpectFailureMentions;
using ::modskill::testing::ReadSingleMember;
using ::modskill::testing::ToBytes;
using Shape = std::vector<int64_t>;
using Values = std::vector<double>;

std::string TempPath(const std::string& file_name) { return TestTempPath("npy_reader_test", file_name); }

std::string ToBigEndian(const std::vector<double>& values) {
  std::string bytes;
  for (double value : values) {
    uint64_t bits;
    std::memcpy(&bits, &value, sizeof(bits));
    for (int i = 7; i >= 0; --i) bytes.push_back(static_cast<char>((bits >> (8 * i)) & 0xFF));
  }
  return bytes;
}

// A .npy file with an arbitrary (possibly broken) header dict, format 1.0.
std::string NpyWithHeader(const std::string& header, const std::string& data) {
  std::string npy("\x93NUMPY\x01\x00", 8);
  npy.push_back(static_cast<char>(header.size() & 0xFF));
  npy.push_back(static_cast<char>(header.size() >> 8));
  return npy + header + data;
}

TEST(ParseNpyTest, TransposesFortranOrderTo3dCOrder) {
  // C-order element (i, j, k) of shape (2, 3, 4) holds 12i + 4j + k; Fortran order puts it at
  // i + 2j + 6k.
  std::vector<float> fortran(24);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 4; ++k) fortran[i + 2 * j + 6 * k] = 12 * i + 4 * j + k;
    }
  }
  absl::StatusOr<NpyArray> array =
      ParseNpy(NpzWriter::MakeNpy("<f4", true, {2, 3, 4}, ToBytes(fortran)), "fortran");
  ASSERT_TRUE(array.ok()) << array.status();
  EXPECT_EQ(array->shape, Shape({2, 3, 4}));
  for (int c = 0; c < 24; ++c) EXPECT_EQ(array->data[c], c) << c;
}

TEST(ParseNpyTest, FortranOrderOfOneDimensionOrEmptyArrayIsUnchanged) {
  absl::StatusOr<NpyArray> vector =
      ParseNpy(NpzWriter::MakeNpy("<f4", true, {3}, ToBytes({7, 8, 9})), "v");
  ASSERT_TRUE(vector.ok()) << vector.status();
  EXPECT_EQ(vector->data, Values({7, 8, 9}));
  absl::StatusOr<NpyArray> empty = ParseNpy(NpzWriter::MakeNpy("<f4", true, {0, 5}, ""), "e");
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_TRUE(empty->data.empty());
}

TEST(ParseNpyTest, SwapsBigEndianFloats) {
  absl::StatusOr<NpyArray> f8 =
      ParseNpy(NpzWriter::MakeNpy(">f8", false, {3}, ToBigEndian({1.5, -2.25, 1e300})), "big f8");
  ASSERT_TRUE(f8.ok()) << f8.status();
  EXPECT_EQ(f8->dtype, ">f8");
  EXPECT_EQ(f8->data, Values({1.5, -2.25, 1e300}));

  // 1.5f is 0x3FC00000, -2.0f is 0xC0000000.
  absl::StatusOr<NpyArray> f4 = ParseNpy(
      NpzWriter::MakeNpy(">f4", false, {2}, std::string("\x3F\xC0\x00\x00\xC0\x00\x00\x00", 8)),
      "big f4");
  ASSERT_TRUE(f4.ok()) << f4.status();
  EXPECT_EQ(f4->data, Values({1.5, -2.0}));
}

TEST(ParseNpyTest, ConvertsIntegerAndBoolDtypes) {
  struct Case {
    std::string descr;
    std::string bytes;
    std::vector<double> expected;
  };
  const std::vector<Case> cases = {
      {"|u1", std::string("\x00\x7F\xFF", 3), {0, 127, 255}},
      {"|i1", std::string("\x80\xFF\x05", 3), {-128, -1, 5}},
      {"|b1", std::string("\x00\x01\x02", 3), {0, 1, 1}},
      {"<i2", std::string("\xD4\xFE\x2C\x01", 4), {-300, 300}},
      {"<u2", std::string("\xFF\xFF", 2), {65535}},
      {"<i4", std::string("\xFB\xFF\xFF\xFF\x07\x00\x00\x00", 8), {-5, 7}},
      {">i4", std::string("\xFF\xFF\xFF\xFB", 4), {-5}},
      {"<u4", std::string("\xFF\xFF\xFF\xFF", 4), {4294967295.0}},
      {"<i8",
       std::string("\xFF\xFF\xFF\xFF\xFF\xFF\xFF\xFF\x00\x00\x00\x00\x00\x01\x00\x00", 16),
       {-1, 1099511627776.0}},
      {"<u8", std::string("\x00\x00\x00\x00\x00\x00\x00\x80", 8), {9223372036854775808.0}},
  };
  for (const Case& c : cases) {
    absl::StatusOr<NpyArray> array = ParseNpy(
        NpzWriter::MakeNpy(c.descr, false, {static_cast<int64_t>(c.expected.size())}, c.bytes),
        c.descr);
    ASSERT_TRUE(array.ok()) << array.status();
    EXPECT_EQ(array->data, c.expected) << c.descr;
    EXPECT_EQ(array->dtype, c.descr);
  }
}

TEST(ParseNpyTest, TakesFirstElementOfStringArrays) {
  absl::StatusOr<NpyArray> bytes =
      ParseNpy(NpzWriter::MakeNpy("|S6", false, {}, std::string("male\0\0", 6)), "S");
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  EXPECT_EQ(bytes->text, "male");

  // ['ab', 'xyz'] as <U3: 'ab' is padded with one NUL code unit.
  const std::string utf32("a\0\0\0b\0\0\0\0\0\0\0x\0\0\0y\0\0\0z\0\0\0", 24);
  absl::StatusOr<NpyArray> unicode = ParseNpy(NpzWriter::MakeNpy("<U3", false, {2}, utf32), "U");
  ASSERT_TRUE(unicode.ok()) << unicode.status();
  EXPECT_EQ(unicode->text, "ab");
  EXPECT_EQ(unicode->shape, Shape({2}));
  EXPECT_EQ(unicode->size(), 2);

  const std::string big_endian("\0\0\0h\0\0\0i", 8);
  absl::StatusOr<NpyArray> big = ParseNpy(NpzWriter::MakeNpy(">U2", false, {}, big_endian), "U");
  ASSERT_TRUE(big.ok()) << big.status();
  EXPECT_EQ(big->text, "hi");
}

TEST(ParseNpyTest, ReadsFormatVersions2And3) {
  const std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }\n";
  for (char major : {'\x02', '\x03'}) {
    std::string npy("\x93NUMPY", 6);
    npy.push_back(major);
    npy.push_back('\0');
    const uint32_t length = header.size();
    npy.append(reinterpret_cast<const char*>(&length), 4);
    npy += header + ToBytes({1.f, 2.f});
    absl::StatusOr<NpyArray> array = ParseNpy(npy, "v2/v3");
    ASSERT_TRUE(array.ok()) << array.status();
    EXPECT_EQ(array->data, Values({1, 2}));
  }
}

TEST(ParseNpyTest, AcceptsPython2LongsAndDoubleQuotes) {
  absl::StatusOr<NpyArray> array = ParseNpy(
      NpyWithHeader("{\"descr\": \"<f4\", \"fortran_order\": False, \"shape\": (1L, 2L)}\n",
                    ToBytes({1.f, 2.f})),
      "py2");
  ASSERT_TRUE(array.ok()) << array.status();
  EXPECT_EQ(array->shape, Shape({1, 2}));
}

TEST(ParseNpyTest, PrefixesMessagesWithWhat) {
  absl::StatusOr<NpyArray> array = ParseNpy("nonsense", "walk.npz: member 'x.npy'");
  ASSERT_FALSE(array.ok());
  EXPECT_TRUE(absl::StartsWith(array.status().message(), "walk.npz: member 'x.npy': "))
      << array.status();
  EXPECT_TRUE(absl::StrContains(array.status().message(), "bad magic")) << array.status();
}

// ---------------------------------------------------------------------------------------------
// Broken .npy members. Every failure must be a status naming the file and the member, never a
// crash.

TEST(NpyMemberErrorTest, DataSizeDoesNotMatchShape) {
  const std::string path = TempPath("walk.npz");
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadSingleMember(
      path, "poses.npy", NpzWriter::MakeNpy("<f4", false, {10, 72}, std::string(1000, '\0')));
  ASSERT_FALSE(arrays.ok());
  EXPECT_EQ(arrays.status().message(),
            absl::StrCat(path,
                         ": member 'poses.npy': data is 1000 bytes but shape (10, 72) of <f4 "
                         "needs 2880"));
  // Trailing bytes are as wrong as missing ones.
  arrays = ReadSingleMember(path, "poses.npy",
                            NpzWriter::MakeNpy("<f8", false, {2}, std::string(24, '\0')));
  ExpectFailureMentions(arrays.status(), {path, "data is 24 bytes but shape (2,) of <f8 needs 16"});
}

TEST(NpyMemberErrorTest, BadMagicAndVersion) {
  const std::string path = TempPath("bad_magic.npz");
  std::string npy = NpzWriter::MakeNpy("<f4", false, {1}, ToBytes({1.f}));
  npy[5] = 'X';
  ExpectFailureMentions(ReadSingleMember(path, "poses.npy", npy).status(),
                        {path, "member 'poses.npy'", "bad magic"});

  npy = NpzWriter::MakeNpy("<f4", false, {1}, ToBytes({1.f}));
  npy[6] = 4;
  ExpectFailureMentions(ReadSingleMember(path, "poses.npy", npy).status(),
                        {path, "member 'poses.npy'", "version 4.0"});

  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy", std::string("\x93NUMPY\x01", 7)).status(),
      {path, "member 'poses.npy'", "truncated"});

  npy = NpzWriter::MakeNpy("<f4", false, {1}, ToBytes({1.f}));
  npy[8] = '\xFF';
  npy[9] = '\xFF';  // header length 65535, past the end of the member
  ExpectFailureMentions(ReadSingleMember(path, "poses.npy", npy).status(),
                        {path, "member 'poses.npy'", "header claims 65535 bytes"});
}

TEST(NpyMemberErrorTest, BadHeaderDicts) {
  const std::vector<std::string> headers = {
      "",
      "not a dict",
      "{'descr': '<f4', 'fortran_order': False}",
      "{'descr': '<f4', 'shape': (1,)}",
      "{'fortran_order': False, 'shape': (1,)}",
      "{'descr': '<f4' 'fortran_order': False, 'shape': (1,)}",
      "{'descr': '<f4', 'fortran_order': Maybe, 'shape': (1,)}",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (1, x)}",
      "{'descr': '<f4', 'fortran_order': False, 'shape': [1]}",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)",
      "{'descr': '<f4, 'fortran_order': False, 'shape': (1,)}",
      "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (1,)}",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), 'extra': 1}",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)} trailing",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999,)}",
  };
  const std::string path = TempPath("bad_header.npz");
  for (const std::string& header : headers) {
    const absl::Status status =
        ReadSingleMember(path, "poses.npy", NpyWithHeader(header, ToBytes({1.f}))).status();
    ExpectFailureMentions(status, {path, "member 'poses.npy'", "bad header dict"});
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << header;
  }
}

TEST(NpyMemberErrorTest, UnsupportedDtypes) {
  const std::vector<std::string> descrs = {"<c16", "|O",  "<M8[ns]", "<f2", "<f16", "f4",
                                           "=f4",  "<V8", "<i3",     "",    "<"};
  const std::string path = TempPath("bad_dtype.npz");
  for (const std::string& descr : descrs) {
    ExpectFailureMentions(
        ReadSingleMember(path, "poses.npy", NpzWriter::MakeNpy(descr, false, {1}, "12345678"))
            .status(),
        {path, "member 'poses.npy'", "unsupported dtype"});
  }
  const std::string structured =
      "{'descr': [('x', '<f4'), ('y', '<f4')], 'fortran_order': False, 'shape': (1,), }";
  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy", NpyWithHeader(structured, "12345678")).status(),
      {path, "member 'poses.npy'", "unsupported dtype", "structured"});
}

TEST(NpyMemberErrorTest, AbsurdShapes) {
  const std::string path = TempPath("absurd_shape.npz");
  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy", NpzWriter::MakeNpy("<f4", false, {-3, 2}, "")).status(),
      {path, "member 'poses.npy'", "shape (-3, 2) has a negative dimension"});
  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy",
                       NpzWriter::MakeNpy("<f4", false, {4294967296, 4294967296, 4}, ""))
          .status(),
      {path, "member 'poses.npy'", "more elements than fit in 64 bits"});
  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy",
                       NpzWriter::MakeNpy("<f8", false, {int64_t{1} << 61, 2}, ""))
          .status(),
      {path, "member 'poses.npy'", "needs more bytes than fit in 64 bits"});
  ExpectFailureMentions(
      ReadSingleMember(path, "poses.npy",
                       NpzWriter::MakeNpy("<f8", false, {1000000000, 1000}, std::string(16, 0)))
          .status(),
      {path, "member 'poses.npy'", "data is 16 bytes but shape (1000000000, 1000) of <f8"});
}

TEST(NpyMemberErrorTest, InvalidCodePointInString) {
  const std::string path = TempPath("bad_unicode.npz");
  ExpectFailureMentions(
      ReadSingleMember(path, "gender.npy",
                       NpzWriter::MakeNpy("<U1", false, {}, std::string("\x00\xD8\x00\x00", 4)))
          .status(),
      {path, "member 'gender.npy'", "invalid code point U+D800"});
}

}  // namespace
}  // namespace modskill
