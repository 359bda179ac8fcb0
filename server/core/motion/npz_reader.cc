#include "server/core/motion/npz_reader.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <system_error>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace modskill {
namespace {

constexpr int64_t kInt64Max = std::numeric_limits<int64_t>::max();
// A 32- or 16-bit field holding all ones means the value is in the zip64 extra or end record.
constexpr uint32_t kZip32Overflow = 0xFFFFFFFFu;
constexpr uint16_t kZip16Overflow = 0xFFFFu;

// Zip record signatures and fixed sizes (PKWARE APPNOTE 4.3).
constexpr uint32_t kLocalHeaderSignature = 0x04034b50;
constexpr uint32_t kCentralHeaderSignature = 0x02014b50;
constexpr uint32_t kEndRecordSignature = 0x06054b50;
constexpr uint32_t kZip64EndRecordSignature = 0x06064b50;
constexpr uint32_t kZip64LocatorSignature = 0x07064b50;
constexpr size_t kLocalHeaderSize = 30;
constexpr size_t kCentralHeaderSize = 46;
constexpr size_t kEndRecordSize = 22;
constexpr size_t kZip64LocatorSize = 20;
constexpr size_t kZip64EndRecordSize = 56;
constexpr size_t kMaxZipCommentSize = 0xFFFF;
constexpr uint16_t kFlagEncrypted = 1 << 0;
constexpr uint16_t kFlagDataDescriptor = 1 << 3;
constexpr uint16_t kMethodStored = 0;
constexpr uint16_t kMethodDeflate = 8;

constexpr absl::string_view kNpyMagic("\x93NUMPY", 6);
// NumPy's NPY_MAXDIMS is 32 (64 since NumPy 2); more is certainly a damaged header.
constexpr size_t kMaxDimensions = 64;

// Zip fields are little-endian. Callers have checked that `at` + width lies inside `bytes`.
uint64_t LoadLittleEndian(absl::string_view bytes, size_t at, int width) {
  uint64_t value = 0;
  for (int i = width - 1; i >= 0; --i) {
    value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
  }
  return value;
}
uint16_t Le16(absl::string_view bytes, size_t at) {
  return static_cast<uint16_t>(LoadLittleEndian(bytes, at, 2));
}
uint32_t Le32(absl::string_view bytes, size_t at) {
  return static_cast<uint32_t>(LoadLittleEndian(bytes, at, 4));
}
uint64_t Le64(absl::string_view bytes, size_t at) { return LoadLittleEndian(bytes, at, 8); }

// True when [offset, offset + length) lies inside [0, limit), without overflowing.
bool Fits(uint64_t offset, uint64_t length, uint64_t limit) {
  return offset <= limit && length <= limit - offset;
}

// Header text and stray bytes for messages: printable ASCII as is, the rest as \xNN.
std::string Printable(absl::string_view bytes) {
  std::string shown;
  for (char c : bytes) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F) {
      shown.push_back(c);
    } else {
      absl::StrAppendFormat(&shown, "\\x%02x", u);
    }
  }
  return shown;
}

absl::Status WithPrefix(const absl::Status& status, absl::string_view prefix) {
  return absl::Status(status.code(), absl::StrCat(prefix, ": ", status.message()));
}

// Shapes are shown the way NumPy prints them, so messages match what the user sees in Python.
std::string PythonShape(const std::vector<int64_t>& shape) {
  if (shape.size() == 1) return absl::StrCat("(", shape[0], ",)");
  return absl::StrCat("(", absl::StrJoin(shape, ", "), ")");
}

// ---------------------------------------------------------------------------------------------
// Reading the file.

absl::StatusOr<std::string> ReadWholeFile(const std::string& path, int64_t max_bytes) {
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) {
    return absl::NotFoundError(absl::StrCat(path, ": no such file"));
  }
  if (std::filesystem::is_directory(status)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory, not an .npz file"));
  }
  std::ifstream file(path, std::ios::binary);
  if (!file.is_open()) {
    const int open_errno = errno;
    const std::string message = absl::StrCat(path, ": cannot open: ", std::strerror(open_errno));
    return open_errno == EACCES ? absl::PermissionDeniedError(message)
                                : absl::UnavailableError(message);
  }
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  file.seekg(0, std::ios::beg);
  if (size < 0 || !file) {
    return absl::UnavailableError(absl::StrCat(path, ": cannot determine the file size"));
  }
  if (size > max_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", size, " bytes, more than the limit of ", max_bytes,
                                                   " (max_decompressed_bytes)"));
  }
  std::string contents(static_cast<size_t>(size), '\0');
  file.read(contents.data(), size);
  if (file.gcount() != size) {
    return absl::UnavailableError(absl::StrCat(path, ": read ", file.gcount(), " of ", size,
                                               " bytes: ", std::strerror(errno)));
  }
  return contents;
}

// ---------------------------------------------------------------------------------------------
// The zip container.

struct ZipEntry {
  std::string name;
  uint16_t flags = 0;
  uint16_t method = 0;
  uint32_t crc = 0;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
  uint64_t local_header_offset = 0;
};

// Sizes and offsets too big for their 32-bit header field are written as 0xFFFFFFFF, with the
// real value in the zip64 extra field (id 1), in the order: uncompressed size, compressed
// size, local header offset. NumPy forces this form in every local header it writes.
absl::Status ApplyZip64Extra(absl::string_view extra, uint64_t* uncompressed_size,
                             uint64_t* compressed_size, uint64_t* local_header_offset) {
  uint64_t* const fields[] = {uncompressed_size, compressed_size, local_header_offset};
  bool any_needed = false;
  for (uint64_t* field : fields) any_needed |= field != nullptr && *field == kZip32Overflow;
  if (!any_needed) return absl::OkStatus();

  size_t pos = 0;
  while (pos + 4 <= extra.size()) {
    const uint16_t id = Le16(extra, pos);
    const uint16_t length = Le16(extra, pos + 2);
    if (pos + 4 + length > extra.size()) break;
    if (id == 1) {
      const absl::string_view block = extra.substr(pos + 4, length);
      size_t at = 0;
      for (uint64_t* field : fields) {
        if (field == nullptr || *field != kZip32Overflow) continue;
        if (at + 8 > block.size()) {
          return absl::DataLossError("zip64 extra field is too short for the sizes it must hold");
        }
        *field = Le64(block, at);
        at += 8;
      }
      return absl::OkStatus();
    }
    pos += 4 + length;
  }
  return absl::DataLossError("sizes are marked as zip64 but the zip64 extra field is missing");
}

// The end record is the last 22 bytes, unless the archive has a comment after it.
size_t FindEndRecord(absl::string_view archive) {
  if (archive.size() < kEndRecordSize) return absl::string_view::npos;
  const size_t last = archive.size() - kEndRecordSize;
  const size_t first = last > kMaxZipCommentSize ? last - kMaxZipCommentSize : 0;
  for (size_t pos = last + 1; pos-- > first;) {
    if (Le32(archive, pos) == kEndRecordSignature &&
        pos + kEndRecordSize + Le16(archive, pos + 20) <= archive.size()) {
      return pos;
    }
  }
  return absl::string_view::npos;
}

// Without an end record the file is either no zip at all or cut short. For the latter, walk
// the local headers from the start to say how far the archive got.
absl::Status ExplainMissingEndRecord(absl::string_view archive) {
  if (archive.empty()) return absl::InvalidArgumentError("file is empty, not an .npz archive");
  if (absl::StartsWith(archive, kNpyMagic)) {
    return absl::InvalidArgumentError(
        "this is a single .npy array, not an .npz archive (read it with ParseNpy)");
  }
  if (archive.size() < 4 || Le32(archive, 0) != kLocalHeaderSignature) {
    return absl::InvalidArgumentError(absl::StrCat(
        "not a zip archive (an .npz file is a zip of .npy members): it starts with \"",
        Printable(archive.substr(0, 8)), "\" and has no end-of-central-directory record"));
  }
  size_t pos = 0;
  while (pos + 4 <= archive.size() && Le32(archive, pos) == kLocalHeaderSignature) {
    if (pos + kLocalHeaderSize > archive.size()) {
      return absl::DataLossError(absl::StrCat(
          "truncated archive: the file ends inside a member's local header at byte ", pos));
    }
    const uint16_t flags = Le16(archive, pos + 6);
    uint64_t compressed_size = Le32(archive, pos + 18);
    uint64_t uncompressed_size = Le32(archive, pos + 22);
    const size_t name_size = Le16(archive, pos + 26);
    const size_t extra_size = Le16(archive, pos + 28);
    const size_t data_start = pos + kLocalHeaderSize + name_size + extra_size;
    if (data_start > archive.size()) {
      return absl::DataLossError(absl::StrCat(
          "truncated archive: the file ends inside a member's local header at byte ", pos));
    }
    const std::string name(archive.substr(pos + kLocalHeaderSize, name_size));
    const absl::string_view extra = archive.substr(pos + kLocalHeaderSize + name_size, extra_size);
    // With a data descriptor the sizes follow the data, so the walk cannot go on.
    if ((flags & kFlagDataDescriptor) != 0 && compressed_size == 0) break;
    if (!ApplyZip64Extra(extra, &uncompressed_size, &compressed_size, nullptr).ok()) break;
    if (!Fits(data_start, compressed_size, archive.size())) {
      return absl::DataLossError(absl::StrFormat(
          "truncated archive: member '%s' needs %d bytes of data but the file ends %d bytes "
          "into it",
          name, compressed_size, archive.size() - data_start));
    }
    pos = data_start + compressed_size;
    if ((flags & kFlagDataDescriptor) != 0) break;
  }
  if (pos + 4 <= archive.size() && Le32(archive, pos) == kCentralHeaderSignature) {
    return absl::DataLossError(absl::StrCat(
        "truncated archive: the file ends inside the central directory, which starts at byte ", pos,
        " of ", archive.size()));
  }
  return absl::DataLossError(
      absl::StrCat("truncated or damaged archive: no end-of-central-directory record in its ",
                   archive.size(), " bytes"));
}

struct CentralDirectory {
  uint64_t offset = 0;
  uint64_t size = 0;
  uint64_t entry_count = 0;
};

absl::StatusOr<CentralDirectory> LocateCentralDirectory(absl::string_view archive) {
  const size_t end_record = FindEndRecord(archive);
  if (end_record == absl::string_view::npos) return ExplainMissingEndRecord(archive);

  uint32_t disk = Le16(archive, end_record + 4);
  uint32_t directory_disk = Le16(archive, end_record + 6);
  CentralDirectory directory;
  directory.entry_count = Le16(archive, end_record + 10);
  directory.size = Le32(archive, end_record + 12);
  directory.offset = Le32(archive, end_record + 16);
  // The central directory must end before the records that describe it.
  uint64_t directory_limit = end_record;

  if (directory.entry_count == kZip16Overflow || directory.size == kZip32Overflow ||
      directory.offset == kZip32Overflow) {
    if (end_record < kZip64LocatorSize ||
        Le32(archive, end_record - kZip64LocatorSize) != kZip64LocatorSignature) {
      return absl::DataLossError(
          "the end record refers to zip64 fields but the zip64 locator before it is missing");
    }
    const size_t locator = end_record - kZip64LocatorSize;
    const uint64_t zip64_end_record = Le64(archive, locator + 8);
    if (!Fits(zip64_end_record, kZip64EndRecordSize, locator) ||
        Le32(archive, zip64_end_record) != kZip64EndRecordSignature) {
      return absl::DataLossError(absl::StrCat("no zip64 end record at offset ", zip64_end_record,
                                              " where the zip64 locator points"));
    }
    disk = Le32(archive, zip64_end_record + 16);
    directory_disk = Le32(archive, zip64_end_record + 20);
    directory.entry_count = Le64(archive, zip64_end_record + 32);
    directory.size = Le64(archive, zip64_end_record + 40);
    directory.offset = Le64(archive, zip64_end_record + 48);
    directory_limit = zip64_end_record;
  }
  if (disk != 0 || directory_disk != 0) {
    return absl::UnimplementedError("multi-disk (split) zip archives are not supported");
  }
  if (!Fits(directory.offset, directory.size, directory_limit)) {
    return absl::DataLossError(
        absl::StrCat("the central directory (", directory.size, " bytes at offset ",
                     directory.offset, ") does not fit before the end record at offset ",
                     directory_limit, "; the archive is truncated or damaged"));
  }
  return directory;
}

absl::StatusOr<std::vector<ZipEntry>> ReadCentralDirectory(absl::string_view archive,
                                                           const CentralDirectory& directory) {
  const absl::string_view records = archive.substr(directory.offset, directory.size);
  std::vector<ZipEntry> entries;
  entries.reserve(std::min<uint64_t>(directory.entry_count, records.size() / kCentralHeaderSize));
  size_t pos = 0;
  for (uint64_t i = 0; i < directory.entry_count; ++i) {
    if (pos + kCentralHeaderSize > records.size() ||
        Le32(records, pos) != kCentralHeaderSignature) {
      return absl::DataLossError(absl::StrCat("central directory entry ", i, " of ",
                                              directory.entry_count, " is missing or damaged"));
    }
    ZipEntry entry;
    entry.flags = Le16(records, pos + 8);
    entry.method = Le16(records, pos + 10);
    entry.crc = Le32(records, pos + 16);
    entry.compressed_size = Le32(records, pos + 20);
    entry.uncompressed_size = Le32(records, pos + 24);
    const size_t name_size = Le16(records, pos + 28);
    const size_t extra_size = Le16(records, pos + 30);
    const size_t comment_size = Le16(records, pos + 32);
    entry.local_header_offset = Le32(records, pos + 42);
    const size_t record_size = kCentralHeaderSize + name_size + extra_size + comment_size;
    if (pos + record_size > records.size()) {
      return absl::DataLossError(absl::StrCat("central directory entry ", i,
                                              " runs past the end of the central directory"));
    }
    entry.name = std::string(records.substr(pos + kCentralHeaderSize, name_size));
    const absl::Status zip64 = ApplyZip64Extra(
        records.substr(pos + kCentralHeaderSize + name_size, extra_size), &entry.uncompressed_size,
        &entry.compressed_size, &entry.local_header_offset);
    if (!zip64.ok()) return WithPrefix(zip64, absl::StrCat("member '", entry.name, "'"));
    entries.push_back(std::move(entry));
    pos += record_size;
  }
  return entries;
}

// Raw deflate (no zlib header), as zip stores it.
absl::StatusOr<std::string> Inflate(absl::string_view compressed, uint64_t expected_size) {
  z_stream stream{};
  if (inflateInit2(&stream, -MAX_WBITS) != Z_OK) {
    return absl::InternalError("zlib inflateInit2 failed");
  }
  struct InflateEnd {
    z_stream* stream;
    ~InflateEnd() { inflateEnd(stream); }
  } inflate_end{&stream};

  // The output grows as data arrives rather than being sized from the header up front, so a
  // damaged size field cannot make us allocate gigabytes for nothing.
  constexpr size_t kOutputChunk = size_t{1} << 20;
  constexpr size_t kInputChunk = size_t{1} << 30;  // avail_in is 32-bit.
  std::string output;
  size_t input_left = compressed.size();
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  while (true) {
    if (stream.avail_in == 0 && input_left > 0) {
      stream.avail_in = static_cast<uInt>(std::min(input_left, kInputChunk));
      input_left -= stream.avail_in;
    }
    const size_t produced = output.size();
    // Leave room for one byte past the expected size, to notice a member that inflates to more.
    const size_t room = static_cast<size_t>(
        std::min<uint64_t>(kOutputChunk, produced < expected_size ? expected_size - produced : 1));
    output.resize(produced + room);
    stream.next_out = reinterpret_cast<Bytef*>(&output[produced]);
    stream.avail_out = static_cast<uInt>(room);
    const int result = inflate(&stream, Z_NO_FLUSH);
    output.resize(produced + room - stream.avail_out);
    if (output.size() > expected_size) {
      return absl::DataLossError(
          absl::StrCat("inflates to more than the ", expected_size, " bytes the archive records"));
    }
    if (result == Z_STREAM_END) break;
    const bool out_of_input = stream.avail_in == 0 && input_left == 0;
    if (result == Z_BUF_ERROR && out_of_input) {
      return absl::DataLossError("compressed data ends before the deflate stream does");
    }
    if (result != Z_OK && result != Z_BUF_ERROR) {
      return absl::DataLossError(absl::StrCat(
          "cannot inflate: ",
          stream.msg != nullptr ? std::string(stream.msg) : absl::StrCat("zlib error ", result)));
    }
  }
  if (output.size() != expected_size) {
    return absl::DataLossError(absl::StrCat("inflates to ", output.size(),
                                            " bytes but the archive records ", expected_size));
  }
  return output;
}

uint32_t Crc32(absl::string_view bytes) {
  return static_cast<uint32_t>(
      crc32_z(0, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

absl::StatusOr<std::string> ExtractMember(absl::string_view archive, const ZipEntry& entry) {
  if ((entry.flags & kFlagEncrypted) != 0) {
    return absl::UnimplementedError("member is encrypted, which is not supported");
  }
  if (entry.method != kMethodStored && entry.method != kMethodDeflate) {
    return absl::UnimplementedError(absl::StrCat("compression method ", entry.method,
                                                 " is not supported (only stored and deflate)"));
  }
  const uint64_t header = entry.local_header_offset;
  if (!Fits(header, kLocalHeaderSize, archive.size()) ||
      Le32(archive, header) != kLocalHeaderSignature) {
    return absl::DataLossError(
        absl::StrCat("no local header at offset ", header, " where the central directory points"));
  }
  const size_t name_size = Le16(archive, header + 26);
  const size_t extra_size = Le16(archive, header + 28);
  if (!Fits(header + kLocalHeaderSize, name_size + extra_size, archive.size())) {
    return absl::DataLossError("local header runs past the end of the file");
  }
  const absl::string_view local_name = archive.substr(header + kLocalHeaderSize, name_size);
  if (local_name != entry.name) {
    return absl::DataLossError(
        absl::StrCat("local header names it '", local_name, "'; the archive is damaged"));
  }
  const uint64_t data_start = header + kLocalHeaderSize + name_size + extra_size;
  if (!Fits(data_start, entry.compressed_size, archive.size())) {
    return absl::DataLossError(absl::StrCat(
        "member data (", entry.compressed_size, " bytes at offset ", data_start,
        ") runs past the end of the file (", archive.size(), " bytes); the archive is truncated"));
  }
  const absl::string_view stored = archive.substr(data_start, entry.compressed_size);

  std::string contents;
  if (entry.method == kMethodStored) {
    if (entry.compressed_size != entry.uncompressed_size) {
      return absl::DataLossError(absl::StrCat("stored (uncompressed) member records ",
                                              entry.compressed_size, " bytes in the archive but ",
                                              entry.uncompressed_size, " bytes of content"));
    }
    contents = std::string(stored);
  } else {
    absl::StatusOr<std::string> inflated = Inflate(stored, entry.uncompressed_size);
    if (!inflated.ok()) return inflated.status();
    contents = *std::move(inflated);
  }
  const uint32_t crc = Crc32(contents);
  if (crc != entry.crc) {
    return absl::DataLossError(absl::StrFormat(
        "CRC-32 mismatch: the archive records 0x%08x but the data hashes to 0x%08x; the file "
        "is corrupt",
        entry.crc, crc));
  }
  return contents;
}

// ---------------------------------------------------------------------------------------------
// The .npy format.

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<int64_t> shape;
};

// Parses the Python dict literal of a .npy header, e.g.
//   {'descr': '<f4', 'fortran_order': False, 'shape': (10, 72), }
// Only the literal forms NumPy writes are accepted, plus the "10L" longs of Python 2.
class HeaderDictParser {
 public:
  explicit HeaderDictParser(absl::string_view text) : text_(text) {}

  absl::StatusOr<NpyHeader> Parse() {
    NpyHeader header;
    bool has_descr = false, has_fortran_order = false, has_shape = false;
    SkipSpace();
    if (absl::Status s = Expect('{'); !s.ok()) return s;
    while (true) {
      SkipSpace();
      if (TryConsume('}')) break;
      const size_t key_pos = pos_;
      std::string key;
      if (absl::Status s = ParseString(&key); !s.ok()) return s;
      SkipSpace();
      if (absl::Status s = Expect(':'); !s.ok()) return s;
      SkipSpace();
      absl::Status value_status;
      bool* seen = nullptr;
      if (key == "descr") {
        seen = &has_descr;
        if (Peek() == '[') {
          return absl::UnimplementedError(
              "unsupported dtype: structured arrays (a descr that lists fields) are not "
              "supported");
        }
        value_status = ParseString(&header.descr);
      } else if (key == "fortran_order") {
        seen = &has_fortran_order;
        value_status = ParseBool(&header.fortran_order);
      } else if (key == "shape") {
        seen = &has_shape;
        value_status = ParseShape(&header.shape);
      } else {
        pos_ = key_pos;
        return Error(absl::StrCat("unexpected key '", key, "'"));
      }
      if (!value_status.ok()) return value_status;
      if (*seen) {
        pos_ = key_pos;
        return Error(absl::StrCat("key '", key, "' appears twice"));
      }
      *seen = true;
      SkipSpace();
      if (TryConsume(',')) continue;
      if (absl::Status s = Expect('}'); !s.ok()) return s;
      break;
    }
    SkipSpace();
    if (pos_ != text_.size()) return Error("unexpected text after the dict");
    if (!has_descr) return Error("key 'descr' is missing");
    if (!has_fortran_order) return Error("key 'fortran_order' is missing");
    if (!has_shape) return Error("key 'shape' is missing");
    return header;
  }

 private:
  char Peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }

  void SkipSpace() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\n' ||
                                   text_[pos_] == '\t' || text_[pos_] == '\r')) {
      ++pos_;
    }
  }

  bool TryConsume(char c) {
    if (Peek() != c || pos_ >= text_.size()) return false;
    ++pos_;
    return true;
  }

  absl::Status Expect(char c) {
    if (TryConsume(c)) return absl::OkStatus();
    return Error(absl::StrCat("expected '", absl::string_view(&c, 1), "'"));
  }

  absl::Status ParseString(std::string* out) {
    const char quote = Peek();
    if (quote != '\'' && quote != '"') return Error("expected a quoted string");
    ++pos_;
    out->clear();
    while (pos_ < text_.size() && text_[pos_] != quote) {
      if (text_[pos_] == '\\' && pos_ + 1 < text_.size()) ++pos_;
      out->push_back(text_[pos_++]);
    }
    if (pos_ >= text_.size()) return Error("unterminated string");
    ++pos_;
    return absl::OkStatus();
  }

  absl::Status ParseBool(bool* out) {
    const absl::string_view rest = text_.substr(pos_);
    if (absl::StartsWith(rest, "True")) {
      *out = true;
      pos_ += 4;
    } else if (absl::StartsWith(rest, "False")) {
      *out = false;
      pos_ += 5;
    } else {
      return Error("expected True or False");
    }
    return absl::OkStatus();
  }

  // A tuple of integers; "(5)" is taken as "(5,)" since no other reading makes sense.
  absl::Status ParseShape(std::vector<int64_t>* shape) {
    if (absl::Status s = Expect('('); !s.ok()) return s;
    shape->clear();
    SkipSpace();
    if (TryConsume(')')) return absl::OkStatus();
    while (true) {
      SkipSpace();
      const bool negative = TryConsume('-');
      if (!absl::ascii_isdigit(static_cast<unsigned char>(Peek()))) {
        return Error("expected an integer in the shape");
      }
      int64_t dimension = 0;
      while (absl::ascii_isdigit(static_cast<unsigned char>(Peek()))) {
        const int digit = text_[pos_++] - '0';
        if (dimension > (kInt64Max - digit) / 10) return Error("shape dimension overflows 64 bits");
        dimension = dimension * 10 + digit;
      }
      if (Peek() == 'L' || Peek() == 'l') ++pos_;  // Python 2 long.
      shape->push_back(negative ? -dimension : dimension);
      if (shape->size() > kMaxDimensions) {
        return Error(absl::StrCat("shape has more than ", kMaxDimensions, " dimensions"));
      }
      SkipSpace();
      if (TryConsume(',')) {
        SkipSpace();
        if (TryConsume(')')) return absl::OkStatus();
        continue;
      }
      return Expect(')');
    }
  }

  absl::Status Error(absl::string_view problem) const {
    constexpr size_t kShownChars = 160;
    const absl::string_view shown = text_.substr(0, kShownChars);
    return absl::InvalidArgumentError(absl::StrCat("bad header dict: ", problem, " at character ",
                                                   pos_, " of \"", Printable(shown),
                                                   text_.size() > kShownChars ? "...\"" : "\""));
  }

  absl::string_view text_;
  size_t pos_ = 0;
};

struct Dtype {
  char kind = 0;          // 'f', 'i', 'u', 'b', 'U' or 'S'.
  int64_t item_size = 0;  // Bytes per element.
  bool big_endian = false;
};

absl::StatusOr<Dtype> ParseDescr(const std::string& descr) {
  const auto unsupported = [&descr]() {
    return absl::UnimplementedError(absl::StrCat(
        "unsupported dtype '", descr,
        "' (supported: f4 f8 i1 i2 i4 i8 u1 u2 u4 u8 b1 in either byte order, and U and S "
        "strings)"));
  };
  if (descr.size() < 2) return unsupported();
  const char byte_order = descr[0];
  Dtype dtype;
  dtype.kind = descr[1];
  int64_t count = 0;
  const absl::string_view digits = absl::string_view(descr).substr(2);
  if (dtype.kind == 'O') {
    return absl::UnimplementedError(
        absl::StrCat("unsupported dtype '", descr,
                     "': it holds pickled Python objects, which cannot be read without Python"));
  }
  if ((byte_order != '<' && byte_order != '>' && byte_order != '|') || digits.empty() ||
      !std::all_of(digits.begin(), digits.end(),
                   [](char c) { return absl::ascii_isdigit(static_cast<unsigned char>(c)); }) ||
      !absl::SimpleAtoi(digits, &count)) {
    return unsupported();
  }
  dtype.big_endian = byte_order == '>';
  dtype.item_size = count;
  switch (dtype.kind) {
    case 'f':
      if (count == 4 || count == 8) return dtype;
      break;
    case 'i':
    case 'u':
      if (count == 1 || count == 2 || count == 4 || count == 8) return dtype;
      break;
    case 'b':
      if (count == 1) return dtype;
      break;
    case 'U':  // UTF-32 code units.
      if (count > kInt64Max / 4) break;
      dtype.item_size = count * 4;
      return dtype;
    case 'S':
      return dtype;
  }
  return unsupported();
}

uint64_t LoadBits(const unsigned char* bytes, int64_t width, bool big_endian) {
  uint64_t bits = 0;
  for (int64_t i = 0; i < width; ++i) {
    bits = (bits << 8) | bytes[big_endian ? i : width - 1 - i];
  }
  return bits;
}

double DecodeNumber(const Dtype& dtype, const unsigned char* bytes) {
  uint64_t bits = LoadBits(bytes, dtype.item_size, dtype.big_endian);
  switch (dtype.kind) {
    case 'f':
      if (dtype.item_size == 4) {
        const uint32_t bits32 = static_cast<uint32_t>(bits);
        float value;
        std::memcpy(&value, &bits32, sizeof(value));
        return value;
      } else {
        double value;
        std::memcpy(&value, &bits, sizeof(value));
        return value;
      }
    case 'i': {
      const int sign_bit = static_cast<int>(dtype.item_size * 8 - 1);
      if (sign_bit < 63 && ((bits >> sign_bit) & 1) != 0) bits |= ~uint64_t{0} << sign_bit;
      int64_t value;
      std::memcpy(&value, &bits, sizeof(value));
      return static_cast<double>(value);
    }
    case 'u':
      return static_cast<double>(bits);
    case 'b':
      return bits != 0 ? 1.0 : 0.0;
  }
  return 0.0;  // ParseDescr admits no other kind.
}

// Fortran order varies the first index fastest. Walk the C-order positions and gather.
std::vector<double> FortranToC(const std::vector<double>& fortran,
                               const std::vector<int64_t>& shape) {
  const int ndim = static_cast<int>(shape.size());
  std::vector<int64_t> fortran_stride(ndim);
  int64_t stride = 1;
  for (int d = 0; d < ndim; ++d) {
    fortran_stride[d] = stride;
    stride *= shape[d];
  }
  std::vector<int64_t> index(ndim, 0);
  std::vector<double> c_order(fortran.size());
  int64_t fortran_offset = 0;
  for (size_t i = 0; i < c_order.size(); ++i) {
    c_order[i] = fortran[fortran_offset];
    for (int d = ndim - 1; d >= 0; --d) {
      if (++index[d] < shape[d]) {
        fortran_offset += fortran_stride[d];
        break;
      }
      fortran_offset -= fortran_stride[d] * (shape[d] - 1);
      index[d] = 0;
    }
  }
  return c_order;
}

void AppendUtf8(uint32_t code_point, std::string* out) {
  if (code_point < 0x80) {
    out->push_back(static_cast<char>(code_point));
  } else if (code_point < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (code_point >> 6)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else if (code_point < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (code_point >> 12)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (code_point >> 18)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((code_point >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code_point & 0x3F)));
  }
}

// NumPy pads string elements with NULs and drops them on access; so do we.
absl::StatusOr<std::string> DecodeFirstString(const Dtype& dtype, absl::string_view element) {
  if (dtype.kind == 'S') {
    const size_t end = element.find_last_not_of('\0');
    return std::string(element.substr(0, end == absl::string_view::npos ? 0 : end + 1));
  }
  std::vector<uint32_t> code_points;
  for (size_t at = 0; at + 4 <= element.size(); at += 4) {
    code_points.push_back(static_cast<uint32_t>(LoadBits(
        reinterpret_cast<const unsigned char*>(element.data() + at), 4, dtype.big_endian)));
  }
  while (!code_points.empty() && code_points.back() == 0) code_points.pop_back();
  std::string utf8;
  for (uint32_t code_point : code_points) {
    if (code_point > 0x10FFFF || (code_point >= 0xD800 && code_point <= 0xDFFF)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("string holds invalid code point U+%X", code_point));
    }
    AppendUtf8(code_point, &utf8);
  }
  return utf8;
}

absl::StatusOr<NpyArray> ParseNpyUnprefixed(absl::string_view bytes, const ResourceLimits& limits) {
  if (!absl::StartsWith(bytes, kNpyMagic)) {
    return absl::InvalidArgumentError(absl::StrCat("not a .npy array: bad magic \"",
                                                   Printable(bytes.substr(0, 6)),
                                                   "\" (expected \"\\x93NUMPY\")"));
  }
  if (bytes.size() < 8) return absl::DataLossError("truncated inside the .npy preamble");
  const int major = static_cast<unsigned char>(bytes[6]);
  const int minor = static_cast<unsigned char>(bytes[7]);
  if ((major < 1 || major > 3) || minor != 0) {
    return absl::UnimplementedError(absl::StrCat(".npy format version ", major, ".", minor,
                                                 " is not supported (only 1.0, 2.0 and 3.0)"));
  }
  // Version 1.0 has a 16-bit header length; 2.0 and 3.0 a 32-bit one (3.0 allows UTF-8).
  const size_t length_width = major == 1 ? 2 : 4;
  const size_t header_start = 8 + length_width;
  if (bytes.size() < header_start) return absl::DataLossError("truncated inside the .npy preamble");
  const uint64_t header_size = LoadLittleEndian(bytes, 8, static_cast<int>(length_width));
  if (!Fits(header_start, header_size, bytes.size())) {
    return absl::DataLossError(absl::StrCat("header claims ", header_size, " bytes but only ",
                                            bytes.size() - header_start, " follow"));
  }
  absl::StatusOr<NpyHeader> header =
      HeaderDictParser(bytes.substr(header_start, header_size)).Parse();
  if (!header.ok()) return header.status();
  absl::StatusOr<Dtype> dtype = ParseDescr(header->descr);
  if (!dtype.ok()) return dtype.status();

  int64_t count = 1;
  bool has_zero_dimension = false;
  for (int64_t dimension : header->shape) {
    if (dimension < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("shape ", PythonShape(header->shape), " has a negative dimension"));
    }
    has_zero_dimension |= dimension == 0;
  }
  // A zero dimension makes the array empty however large the others are.
  if (has_zero_dimension) count = 0;
  for (int64_t dimension : header->shape) {
    if (has_zero_dimension) break;
    if (count > kInt64Max / dimension) {
      return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header->shape),
                                                     " has more elements than fit in 64 bits"));
    }
    count *= dimension;
  }
  if (dtype->item_size != 0 && count > kInt64Max / dtype->item_size) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header->shape), " of ",
                                                   header->descr,
                                                   " needs more bytes than fit in 64 bits"));
  }
  const uint64_t needed = static_cast<uint64_t>(count * dtype->item_size);
  const absl::string_view data = bytes.substr(header_start + header_size);
  if (data.size() != needed) {
    return absl::InvalidArgumentError(absl::StrCat("data is ", data.size(), " bytes but shape ",
                                                   PythonShape(header->shape), " of ",
                                                   header->descr, " needs ", needed));
  }
  // Motion matrices hold one row per frame: more rows than a clip may have frames is refused
  // here, before the conversion to double doubles the member's memory (a 117 KB archive of
  // 200,000 zero frames peaked at 196 MB through AddMotions without it).
  if (header->shape.size() >= 2 && header->shape[0] > limits.max_clip_frames) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header->shape), ": ", header->shape[0],
                                                   " frames, more than the limit of ", limits.max_clip_frames,
                                                   " (max_clip_frames)"));
  }

  // Numbers are held as doubles: a u1 array takes eight times its bytes in the file.
  const bool numeric = dtype->kind != 'U' && dtype->kind != 'S';
  if (numeric && count > limits.max_npz_member_bytes / static_cast<int64_t>(sizeof(double))) {
    return absl::InvalidArgumentError(absl::StrCat("shape ", PythonShape(header->shape), " holds ", count,
                                                   " numbers, more than the ", limits.max_npz_member_bytes,
                                                   " bytes as doubles allowed per array (max_npz_member_bytes)"));
  }

  NpyArray array;
  array.shape = header->shape;
  array.dtype = header->descr;
  if (dtype->kind == 'U' || dtype->kind == 'S') {
    if (count > 0) {
      absl::StatusOr<std::string> text =
          DecodeFirstString(*dtype, data.substr(0, static_cast<size_t>(dtype->item_size)));
      if (!text.ok()) return text.status();
      array.text = *std::move(text);
    }
    return array;
  }
  array.data.resize(static_cast<size_t>(count));
  const auto* element = reinterpret_cast<const unsigned char*>(data.data());
  for (double& value : array.data) {
    value = DecodeNumber(*dtype, element);
    element += dtype->item_size;
  }
  if (header->fortran_order && array.shape.size() >= 2) {
    array.data = FortranToC(array.data, array.shape);
  }
  return array;
}

absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ParseNpzUnguarded(absl::string_view archive,
                                                                             absl::string_view what,
                                                                             const ResourceLimits& limits) {
  absl::StatusOr<CentralDirectory> directory = LocateCentralDirectory(archive);
  if (!directory.ok()) return WithPrefix(directory.status(), what);
  absl::StatusOr<std::vector<ZipEntry>> entries = ReadCentralDirectory(archive, *directory);
  if (!entries.ok()) return WithPrefix(entries.status(), what);

  // The sizes the archive records are checked before anything is inflated; Inflate then refuses
  // to produce more than the recorded size, so a bomb stops at the bound.
  uint64_t total = 0;
  for (const ZipEntry& entry : *entries) {
    // Data that cannot lie in the file is reported by ExtractMember, before it inflates anything.
    if (entry.compressed_size > archive.size()) continue;
    const std::string member = absl::StrCat(what, ": member '", entry.name, "'");
    if (entry.uncompressed_size > static_cast<uint64_t>(limits.max_npz_member_bytes)) {
      return absl::InvalidArgumentError(absl::StrCat(member, ": inflates to ", entry.uncompressed_size,
                                                     " bytes, more than the limit of ", limits.max_npz_member_bytes,
                                                     " per member (max_npz_member_bytes)"));
    }
    total += entry.uncompressed_size;
    if (total > static_cast<uint64_t>(limits.max_decompressed_bytes)) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": members inflate to more than the limit of ",
                                                     limits.max_decompressed_bytes,
                                                     " bytes (max_decompressed_bytes)"));
    }
  }

  absl::flat_hash_map<std::string, NpyArray> arrays;
  for (const ZipEntry& entry : *entries) {
    if (absl::EndsWith(entry.name, "/")) continue;  // A directory entry holds no data.
    const std::string member = absl::StrCat(what, ": member '", entry.name, "'");
    absl::StatusOr<std::string> contents = ExtractMember(archive, entry);
    if (!contents.ok()) return WithPrefix(contents.status(), member);
    absl::StatusOr<NpyArray> array = ParseNpy(*contents, member, limits);
    if (!array.ok()) return array.status();
    std::string key = entry.name;
    if (absl::EndsWith(key, ".npy")) key.resize(key.size() - 4);
    if (!arrays.emplace(key, *std::move(array)).second) {
      return absl::InvalidArgumentError(
          absl::StrCat(member, ": the archive holds '", key, "' more than once"));
    }
  }
  return arrays;
}

}  // namespace

int64_t NpyArray::size() const {
  int64_t count = 1;
  for (int64_t dimension : shape) count *= dimension;
  return count;
}

absl::StatusOr<NpyArray> ParseNpy(absl::string_view bytes, absl::string_view what, const ResourceLimits& limits) {
  absl::StatusOr<NpyArray> array = ParseNpyUnprefixed(bytes, limits);
  if (!array.ok()) return WithPrefix(array.status(), what);
  return array;
}

absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ParseNpz(absl::string_view archive, absl::string_view what,
                                                                    const ResourceLimits& limits) {
  // Sizes are checked against the limits before anything is allocated, so this only guards
  // against a machine already short of memory.
  try {
    return ParseNpzUnguarded(archive, what, limits);
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(what, ": out of memory while reading"));
  }
}

absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ReadNpz(const std::string& path,
                                                                   const ResourceLimits& limits) {
  absl::StatusOr<std::string> archive = ReadWholeFile(path, limits.max_decompressed_bytes);
  if (!archive.ok()) return archive.status();
  return ParseNpz(*archive, path, limits);
}

}  // namespace modskill
