#include "server/core/motion/npz_reader.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "gtest/gtest.h"
#include "tests/npz_test_writer.h"
#include "tests/test_files.h"

namespace modskill {
namespace {

using NpzWriter = ::modskill::testing::NpzWriter;
using Shape = std::vector<int64_t>;
using Values = std::vector<double>;

std::string TempPath(const std::string& file_name) { return TestTempPath("npz_reader_test", file_name); }

std::string ToBytes(const std::vector<float>& values) {
  std::string bytes(values.size() * sizeof(float), '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());  // The test host is little-endian.
  return bytes;
}

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

// Writes one member into an archive and reads the archive back.
absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ReadSingleMember(
    const std::string& path, const std::string& member_name, const std::string& npy_bytes,
    bool compress = false) {
  NpzWriter writer;
  writer.AddRawMember(member_name, npy_bytes);
  EXPECT_TRUE(writer.Write(path, compress));
  return ReadNpz(path);
}

// The archive's end record: where the central directory starts (last 22 bytes, no comment).
uint32_t CentralDirectoryOffset(const std::string& archive) {
  uint32_t offset = 0;
  std::memcpy(&offset, archive.data() + archive.size() - 22 + 16, 4);
  return offset;
}

// ---------------------------------------------------------------------------------------------
// Round trips through NpzWriter, stored and deflated.

class NpzRoundTripTest : public ::testing::TestWithParam<bool> {
 protected:
  bool compress() const { return GetParam(); }
};

TEST_P(NpzRoundTripTest, ReadsAmassLikeArchive) {
  const std::vector<float> poses = {0.f, 1.5f, -2.25f, 3.f, 4.f,  5.f,
                                    6.f, 7.f,  8.f,    9.f, 10.f, 11.f};
  std::vector<double> betas(16);
  for (int i = 0; i < 16; ++i) betas[i] = 0.1 * i - 0.7;
  NpzWriter writer;
  writer.AddF32("poses", {3, 4}, poses);
  writer.AddF64("trans", {2, 3}, {1e-300, -1.0, 2.0, 3.0, 1e300, -0.0});
  writer.AddF64("betas", {16}, betas);
  writer.AddF64("mocap_framerate", {}, {120.0});
  writer.AddF32("empty", {0, 3}, {});
  writer.AddString("gender", "female");
  const std::string path = TempPath("amass_like.npz");
  ASSERT_TRUE(writer.Write(path, compress()));

  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_EQ(arrays->size(), 6u);

  const NpyArray& read_poses = arrays->at("poses");
  EXPECT_EQ(read_poses.shape, Shape({3, 4}));
  EXPECT_EQ(read_poses.dtype, "<f4");
  EXPECT_EQ(read_poses.size(), 12);
  ASSERT_EQ(read_poses.data.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(read_poses.data[i], poses[i]);
  EXPECT_TRUE(read_poses.text.empty());

  const NpyArray& trans = arrays->at("trans");
  EXPECT_EQ(trans.dtype, "<f8");
  EXPECT_EQ(trans.shape, Shape({2, 3}));
  EXPECT_EQ(trans.data, Values({1e-300, -1.0, 2.0, 3.0, 1e300, -0.0}));
  EXPECT_TRUE(std::signbit(trans.data[5]));

  EXPECT_EQ(arrays->at("betas").shape, Shape({16}));
  EXPECT_EQ(arrays->at("betas").data, betas);

  const NpyArray& framerate = arrays->at("mocap_framerate");
  EXPECT_TRUE(framerate.shape.empty());
  EXPECT_EQ(framerate.size(), 1);
  EXPECT_EQ(framerate.data, Values({120.0}));

  EXPECT_EQ(arrays->at("empty").shape, Shape({0, 3}));
  EXPECT_EQ(arrays->at("empty").size(), 0);
  EXPECT_TRUE(arrays->at("empty").data.empty());

  const NpyArray& gender = arrays->at("gender");
  EXPECT_EQ(gender.text, "female");
  EXPECT_EQ(gender.dtype, "<U6");
  EXPECT_TRUE(gender.shape.empty());
  EXPECT_TRUE(gender.data.empty());
}

TEST_P(NpzRoundTripTest, ReadsNonAsciiAndEmptyStrings) {
  NpzWriter writer;
  writer.AddString("name", "m\xC3\xA4nnlich \xE2\x9C\x93 \xF0\x9D\x84\x9E");  // männlich ✓ 𝄞
  writer.AddString("nothing", "");
  const std::string path = TempPath("strings.npz");
  ASSERT_TRUE(writer.Write(path, compress()));
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_EQ(arrays->at("name").text, "m\xC3\xA4nnlich \xE2\x9C\x93 \xF0\x9D\x84\x9E");
  EXPECT_EQ(arrays->at("name").dtype, "<U12");
  EXPECT_EQ(arrays->at("nothing").text, "");
}

TEST_P(NpzRoundTripTest, ReadsZip64Records) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 2}, {1.f, 2.f, 3.f, 4.f});
  writer.AddString("gender", "male");
  const std::string path = TempPath("zip64.npz");
  WriteBytes(path, writer.Serialize(compress(), /*zip64_records=*/true));
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_EQ(arrays->at("poses").data, Values({1.0, 2.0, 3.0, 4.0}));
  EXPECT_EQ(arrays->at("gender").text, "male");
}

TEST_P(NpzRoundTripTest, ReadsEmptyArchive) {
  const std::string path = TempPath("empty.npz");
  ASSERT_TRUE(NpzWriter().Write(path, compress()));
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_TRUE(arrays->empty());
}

TEST_P(NpzRoundTripTest, ReadsFortranOrderMember) {
  // C order [[0, 1, 2], [3, 4, 5]] laid out column by column.
  const std::string path = TempPath("fortran.npz");
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadSingleMember(
      path, "m.npy", NpzWriter::MakeNpy("<f4", true, {2, 3}, ToBytes({0, 3, 1, 4, 2, 5})),
      compress());
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_EQ(arrays->at("m").shape, Shape({2, 3}));
  EXPECT_EQ(arrays->at("m").data, Values({0, 1, 2, 3, 4, 5}));
}

INSTANTIATE_TEST_SUITE_P(StoredAndDeflated, NpzRoundTripTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "Deflated" : "Stored";
                         });

TEST(NpzWriterTest, RejectsValuesThatDoNotMatchTheShape) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 3}, {1.f, 2.f});
  EXPECT_FALSE(writer.Write(TempPath("mismatch.npz"), false));
}

// ---------------------------------------------------------------------------------------------
// Archives written by NumPy 1.24 itself:
//   np.savez(f, poses=np.arange(6, dtype=np.float32).reshape(2, 3),
//            gender=np.array('female'), mocap_framerate=np.array(120.0))
// NumPy puts a zip64 extra field in every local header, which the reader must skip.

constexpr char kNumpySavezHex[] =
    "504b0304140000000000000021004fe9002a980000009800000009001400706f7365732e6e70790100100098"
    "000000000000009800000000000000934e554d5059010076007b276465736372273a20273c6634272c202766"
    "6f727472616e5f6f72646572273a2046616c73652c20277368617065273a2028322c2033292c207d20202020"
    "2020202020202020202020202020202020202020202020202020202020202020202020202020202020202020"
    "202020202020202020200a000000000000803f0000004000004040000080400000a040504b03041400000000"
    "0000002100a34aba7998000000980000000a00140067656e6465722e6e707901001000980000000000000098"
    "00000000000000934e554d5059010076007b276465736372273a20273c5536272c2027666f727472616e5f6f"
    "72646572273a2046616c73652c20277368617065273a2028292c207d20202020202020202020202020202020"
    "2020202020202020202020202020202020202020202020202020202020202020202020202020202020202020"
    "20200a66000000650000006d000000610000006c00000065000000504b030414000000000000002100eb016e"
    "d38800000088000000130014006d6f6361705f6672616d65726174652e6e7079010010008800000000000000"
    "8800000000000000934e554d5059010076007b276465736372273a20273c6638272c2027666f727472616e5f"
    "6f72646572273a2046616c73652c20277368617065273a2028292c207d202020202020202020202020202020"
    "2020202020202020202020202020202020202020202020202020202020202020202020202020202020202020"
    "2020200a0000000000005e40504b01021403140000000000000021004fe9002a980000009800000009000000"
    "0000000000000000800100000000706f7365732e6e7079504b0102140314000000000000002100a34aba7998"
    "000000980000000a00000000000000000000008001d300000067656e6465722e6e7079504b01021403140000"
    "00000000002100eb016ed388000000880000001300000000000000000000008001a70100006d6f6361705f66"
    "72616d65726174652e6e7079504b05060000000003000300b0000000740200000000";

// The same arrays through np.savez_compressed.
constexpr char kNumpySavezCompressedHex[] =
    "504b0304140000000800000021004fe9002a550000009800000009001400706f7365732e6e70790100100098"
    "0000000000000055000000000000009bec17ea1b10c9c850c650ad9e925a9c5ca46ea5a06e9366a2aea3a09e"
    "965f54529498179f5f94920a12774bcc294e058a17672416a402f91a463a0ac69a3a0ab50a64032e063068b0"
    "07120e4004c40d40bcc00100504b030414000000080000002100a34aba7950000000980000000a0014006765"
    "6e6465722e6e707901001000980000000000000050000000000000009bec17ea1b10c9c850c650ad9e925a9c"
    "5ca46ea5a06e136aa6aea3a09e965f54529498179f5f94920a12774bcc294e058a17672416a402f91a9a3a0a"
    "b50a1401ae340606865420ce05e24420ce81f201504b030414000000080000002100eb016ed3470000008800"
    "0000130014006d6f6361705f6672616d65726174652e6e707901001000880000000000000047000000000000"
    "009bec17ea1b10c9c850c650ad9e925a9c5ca46ea5a06e9366a1aea3a09e965f54529498179f5f94920a1277"
    "4bcc294e058a17672416a402f91a9a3a0ab50a14012e063088730000504b0102140314000000080000002100"
    "4fe9002a5500000098000000090000000000000000000000800100000000706f7365732e6e7079504b010214"
    "0314000000080000002100a34aba7950000000980000000a000000000000000000000080019000000067656e"
    "6465722e6e7079504b0102140314000000080000002100eb016ed34700000088000000130000000000000000"
    "00000080011c0100006d6f6361705f6672616d65726174652e6e7079504b05060000000003000300b0000000"
    "a80100000000";

class NumpyWrittenArchiveTest : public ::testing::TestWithParam<const char*> {};

TEST_P(NumpyWrittenArchiveTest, ReadsEveryMember) {
  const std::string path = TempPath("numpy.npz");
  WriteBytes(path, absl::HexStringToBytes(GetParam()));
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  ASSERT_EQ(arrays->size(), 3u);
  EXPECT_EQ(arrays->at("poses").shape, Shape({2, 3}));
  EXPECT_EQ(arrays->at("poses").data, Values({0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(arrays->at("gender").text, "female");
  EXPECT_EQ(arrays->at("mocap_framerate").data, Values({120.0}));
}

INSTANTIATE_TEST_SUITE_P(SavezAndSavezCompressed, NumpyWrittenArchiveTest,
                         ::testing::Values(kNumpySavezHex, kNumpySavezCompressedHex));

// ---------------------------------------------------------------------------------------------
// The .npy format on its own.

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
// Broken files. Every failure must be a status naming the file (and the member, when there
// is one), never a crash.

void ExpectFailureMentions(const absl::Status& status, const std::vector<std::string>& parts) {
  EXPECT_FALSE(status.ok());
  for (const std::string& part : parts) {
    EXPECT_TRUE(absl::StrContains(status.message(), part)) << "'" << part << "' not in: " << status;
  }
}

TEST(NpzErrorTest, MissingFile) {
  const std::string path = TempPath("does_not_exist.npz");
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
  EXPECT_EQ(arrays.status().code(), absl::StatusCode::kNotFound);
  ExpectFailureMentions(arrays.status(), {path, "no such file"});
}

TEST(NpzErrorTest, DirectoryEmptyFileTextFileAndBareNpy) {
  const std::string directory = TempPath("a_directory.npz");
  std::filesystem::create_directories(directory);
  ExpectFailureMentions(ReadNpz(directory).status(), {directory, "directory"});

  const std::string empty = TempPath("empty.npz");
  WriteBytes(empty, "");
  ExpectFailureMentions(ReadNpz(empty).status(), {empty, "empty"});

  const std::string text = TempPath("text.npz");
  WriteBytes(text, "poses,trans\n1,2\n");
  ExpectFailureMentions(ReadNpz(text).status(), {text, "not a zip archive"});

  const std::string npy = TempPath("bare.npz");
  WriteBytes(npy, NpzWriter::MakeNpy("<f4", false, {1}, ToBytes({1.f})));
  ExpectFailureMentions(ReadNpz(npy).status(), {npy, ".npy"});
}

class TruncatedArchiveTest : public ::testing::TestWithParam<bool> {};

TEST_P(TruncatedArchiveTest, EveryTruncationIsAnError) {
  NpzWriter writer;
  writer.AddF32("poses", {4, 3}, std::vector<float>(12, 0.5f));
  writer.AddString("gender", "neutral");
  const std::string archive = writer.Serialize(/*compress=*/GetParam());
  const std::string path = TempPath("truncated.npz");
  for (size_t length = 0; length < archive.size(); ++length) {
    WriteBytes(path, archive.substr(0, length));
    const absl::Status status = ReadNpz(path).status();
    ASSERT_FALSE(status.ok()) << "length " << length;
    ASSERT_TRUE(absl::StrContains(status.message(), path)) << "length " << length << ": " << status;
  }
  // Cut inside the first member's data: the message says which member.
  WriteBytes(path, archive.substr(0, 100));
  ExpectFailureMentions(ReadNpz(path).status(), {path, "truncated", "'poses.npy'"});
  // Cut inside the central directory.
  WriteBytes(path, archive.substr(0, CentralDirectoryOffset(archive) + 10));
  ExpectFailureMentions(ReadNpz(path).status(), {path, "truncated", "central directory"});
}

INSTANTIATE_TEST_SUITE_P(StoredAndDeflated, TruncatedArchiveTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "Deflated" : "Stored";
                         });

TEST(NpzErrorTest, FlippedByteBreaksCrc) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 3}, {1, 2, 3, 4, 5, 6});
  std::string archive = writer.Serialize(/*compress=*/false);
  archive[CentralDirectoryOffset(archive) - 1] ^= 0x40;  // Last data byte of the only member.
  const std::string path = TempPath("bad_crc.npz");
  WriteBytes(path, archive);
  const absl::Status status = ReadNpz(path).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  ExpectFailureMentions(status, {path, "member 'poses.npy'", "CRC-32 mismatch"});
}

TEST(NpzErrorTest, FlippedByteInDeflatedMemberIsCaught) {
  NpzWriter writer;
  std::vector<float> values(300);
  for (size_t i = 0; i < values.size(); ++i) values[i] = std::sin(0.1f * i);
  writer.AddF32("poses", {100, 3}, values);
  const std::string archive = writer.Serialize(/*compress=*/true);
  const size_t data_start = 30 + std::strlen("poses.npy");
  const size_t data_end = CentralDirectoryOffset(archive);
  const std::string path = TempPath("bad_deflate.npz");
  int failures = 0;
  for (size_t at = data_start; at < data_end; ++at) {
    std::string broken = archive;
    broken[at] ^= 0x10;
    WriteBytes(path, broken);
    absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ReadNpz(path);
    if (arrays.ok()) {
      // Some bits (padding after the final block) do not matter; then the data must be intact.
      const std::vector<double>& read = arrays->at("poses").data;
      ASSERT_EQ(read.size(), values.size()) << "byte " << at;
      for (size_t i = 0; i < values.size(); ++i) ASSERT_EQ(read[i], values[i]) << "byte " << at;
    } else {
      ++failures;
      ExpectFailureMentions(arrays.status(), {path, "member 'poses.npy'"});
    }
  }
  EXPECT_GT(failures, static_cast<int>(data_end - data_start) / 2);
}

TEST(NpzErrorTest, CentralDirectoryClaimsMoreDataThanTheFileHolds) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 3}, {1, 2, 3, 4, 5, 6});
  std::string archive = writer.Serialize(/*compress=*/false);
  const size_t central = CentralDirectoryOffset(archive);
  const uint32_t huge = 0x7FFFFFFF;
  std::memcpy(&archive[central + 20], &huge, 4);  // compressed size
  std::memcpy(&archive[central + 24], &huge, 4);  // uncompressed size
  const std::string path = TempPath("claims_too_much.npz");
  WriteBytes(path, archive);
  ExpectFailureMentions(ReadNpz(path).status(),
                        {path, "member 'poses.npy'", "runs past the end of the file"});
}

TEST(NpzErrorTest, DeflatedSizeFieldTooLargeOrTooSmall) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 3}, {1, 2, 3, 4, 5, 6});
  const std::string archive = writer.Serialize(/*compress=*/true);
  const size_t central = CentralDirectoryOffset(archive);
  const std::string path = TempPath("wrong_uncompressed_size.npz");
  for (uint32_t claimed : {0u, 10u, 0x7FFFFFFFu}) {
    std::string broken = archive;
    std::memcpy(&broken[central + 24], &claimed, 4);
    WriteBytes(path, broken);
    ExpectFailureMentions(ReadNpz(path).status(), {path, "member 'poses.npy'", "inflates to"});
  }
}

TEST(NpzErrorTest, UnsupportedCompressionMethod) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  std::string archive = writer.Serialize(/*compress=*/false);
  archive[8] = 12;                                     // local header: bzip2
  archive[CentralDirectoryOffset(archive) + 10] = 12;  // central directory: bzip2
  const std::string path = TempPath("bzip2.npz");
  WriteBytes(path, archive);
  ExpectFailureMentions(ReadNpz(path).status(),
                        {path, "member 'poses.npy'", "compression method 12"});
}

TEST(NpzErrorTest, DataSizeDoesNotMatchShape) {
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

TEST(NpzErrorTest, BadMagicAndVersion) {
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

TEST(NpzErrorTest, BadHeaderDicts) {
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

TEST(NpzErrorTest, UnsupportedDtypes) {
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

TEST(NpzErrorTest, AbsurdShapes) {
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

TEST(NpzErrorTest, InvalidCodePointInString) {
  const std::string path = TempPath("bad_unicode.npz");
  ExpectFailureMentions(
      ReadSingleMember(path, "gender.npy",
                       NpzWriter::MakeNpy("<U1", false, {}, std::string("\x00\xD8\x00\x00", 4)))
          .status(),
      {path, "member 'gender.npy'", "invalid code point U+D800"});
}

TEST(NpzErrorTest, DuplicateMember) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  writer.AddF32("poses", {1}, {2});
  const std::string path = TempPath("duplicate.npz");
  ASSERT_TRUE(writer.Write(path, false));
  ExpectFailureMentions(ReadNpz(path).status(), {path, "'poses'", "more than once"});
}

}  // namespace
}  // namespace modskill
