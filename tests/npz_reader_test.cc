// The .npz container: round trips through NpzWriter and archives NumPy wrote, in memory and on
// disk, zip64 records, and broken, truncated, lying or hostile archives (the .npy members
// themselves are tests/npy_reader_test.cc's).
#include "server/core/motion/npz_reader.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
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

std::string TempPath(const std::string& file_name) { return TestTempPath("npz_reader_test", file_name); }

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
// Broken files. Every failure must be a status naming the file (and the member, when there
// is one), never a crash.

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

TEST(NpzErrorTest, DuplicateMember) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  writer.AddF32("poses", {1}, {2});
  const std::string path = TempPath("duplicate.npz");
  ASSERT_TRUE(writer.Write(path, false));
  ExpectFailureMentions(ReadNpz(path).status(), {path, "'poses'", "more than once"});
}

// ---------------------------------------------------------------------------------------------
// Archives in memory (AddMotions uploads) and hostile records.

// Overwrites `width` bytes of `archive` at `at` with `value`, little-endian.
void Patch(std::string* archive, size_t at, uint64_t value, int width) {
  for (int i = 0; i < width; ++i) (*archive)[at + i] = static_cast<char>((value >> (8 * i)) & 0xFF);
}

TEST(NpzMemoryTest, ParsesBytesAndNamesThemInMessages) {
  NpzWriter writer;
  writer.AddF32("poses", {1, 2}, {1.f, 2.f});
  const std::string archive = writer.Serialize(/*compress=*/true);
  absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> arrays = ParseNpz(archive, "upload.npz");
  ASSERT_TRUE(arrays.ok()) << arrays.status();
  EXPECT_EQ(arrays->at("poses").data, Values({1.0, 2.0}));
  ExpectFailureMentions(ParseNpz(archive.substr(0, 60), "upload.npz").status(),
                        {"upload.npz", "truncated", "'poses.npy'"});
  ExpectFailureMentions(ParseNpz("", "upload.npz").status(), {"upload.npz", "empty"});
}

TEST(NpzErrorTest, EncryptedMemberIsUnsupported) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  std::string archive = writer.Serialize(/*compress=*/false);
  archive[6] |= 1;                                    // local header: encrypted
  archive[CentralDirectoryOffset(archive) + 8] |= 1;  // central directory: encrypted
  const absl::Status status = ParseNpz(archive, "secret.npz").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnimplemented);
  ExpectFailureMentions(status, {"secret.npz", "member 'poses.npy'", "encrypted"});
}

TEST(NpzErrorTest, CentralDirectoryPointsAtNoLocalHeader) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  writer.AddF32("trans", {1}, {2});
  std::string archive = writer.Serialize(/*compress=*/false);
  const size_t second_entry = archive.find("PK\x01\x02", CentralDirectoryOffset(archive) + 4);
  ASSERT_NE(second_entry, std::string::npos);
  Patch(&archive, second_entry + 42, 7, 4);  // local header offset: into the first member
  const absl::Status status = ParseNpz(archive, "pointer.npz").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  ExpectFailureMentions(status, {"pointer.npz", "member 'trans.npy'"});
}

TEST(NpzErrorTest, StoredMemberWhoseSizesDisagree) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  std::string archive = writer.Serialize(/*compress=*/false);
  const size_t central = CentralDirectoryOffset(archive);
  Patch(&archive, central + 24, 8, 4);  // uncompressed size
  ExpectFailureMentions(ParseNpz(archive, "stored.npz").status(),
                        {"stored.npz", "member 'poses.npy'", "stored (uncompressed) member records"});
}

// The zip64 extra of the central directory claims a terabyte: refused from the record, before
// anything is inflated.
TEST(NpzBombTest, Zip64RecordedSizeBeyondTheLimit) {
  NpzWriter writer;
  writer.AddF32("poses", {2, 2}, {1.f, 2.f, 3.f, 4.f});
  std::string archive = writer.Serialize(/*compress=*/true, /*zip64_records=*/true);
  const size_t central = archive.find("PK\x01\x02");
  ASSERT_NE(central, std::string::npos);
  Patch(&archive, central + 46 + std::strlen("poses.npy") + 4, uint64_t{1} << 40, 8);
  const absl::Status status = ParseNpz(archive, "bomb.npz").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  ExpectFailureMentions(status, {"bomb.npz", "member 'poses.npy'", "max_npz_member_bytes"});
}

// A zip64 end record may claim any number of entries; none may be allocated for on its word.
TEST(NpzBombTest, Zip64EntryCountBeyondTheCentralDirectory) {
  NpzWriter writer;
  writer.AddF32("poses", {1}, {1});
  std::string archive = writer.Serialize(/*compress=*/false, /*zip64_records=*/true);
  const size_t end_record = archive.find("PK\x06\x06");
  ASSERT_NE(end_record, std::string::npos);
  Patch(&archive, end_record + 24, uint64_t{1} << 40, 8);  // entries on this disk
  Patch(&archive, end_record + 32, uint64_t{1} << 40, 8);  // entries in all
  const absl::Status status = ParseNpz(archive, "count.npz").status();
  EXPECT_FALSE(status.ok());
  EXPECT_TRUE(absl::StartsWith(status.message(), "count.npz: ")) << status;
}

}  // namespace
}  // namespace modskill
