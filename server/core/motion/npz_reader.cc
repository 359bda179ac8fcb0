#include "server/core/motion/npz_reader.h"

#include <zip.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <new>
#include <system_error>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/shown_value.h"

namespace modskill {
namespace {

absl::Status WithPrefix(const absl::Status& status, absl::string_view prefix) {
  return absl::Status(status.code(), absl::StrCat(prefix, ": ", status.message()));
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
// When libzip finds no archive: a file that is no zip at all, or one cut short. For the latter,
// the local headers from the start say how far the archive got (for the message only; nothing
// is read from them).

constexpr uint32_t kLocalHeaderSignature = 0x04034b50;
constexpr uint32_t kCentralHeaderSignature = 0x02014b50;
constexpr size_t kLocalHeaderSize = 30;
constexpr uint16_t kFlagDataDescriptor = 1 << 3;
// A 32-bit size holding all ones is in a zip64 extra field, which the walk does not follow.
constexpr uint32_t kZip32Overflow = 0xFFFFFFFFu;

// Callers have checked that `at` + 4 lies inside `bytes`.
uint32_t Le32(absl::string_view bytes, size_t at) {
  uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
  return value;
}
uint16_t Le16(absl::string_view bytes, size_t at) {
  return static_cast<uint16_t>(static_cast<unsigned char>(bytes[at]) |
                               (static_cast<unsigned char>(bytes[at + 1]) << 8));
}

absl::Status ExplainTruncation(absl::string_view archive) {
  size_t pos = 0;
  while (pos + 4 <= archive.size() && Le32(archive, pos) == kLocalHeaderSignature) {
    const size_t name_at = pos + kLocalHeaderSize;
    if (name_at > archive.size() ||
        name_at + Le16(archive, pos + 26) + Le16(archive, pos + 28) > archive.size()) {
      return absl::DataLossError(absl::StrCat(
          "truncated archive: the file ends inside a member's local header at byte ", pos));
    }
    const uint16_t flags = Le16(archive, pos + 6);
    const uint32_t compressed_size = Le32(archive, pos + 18);
    const size_t name_size = Le16(archive, pos + 26);
    const size_t data_start = name_at + name_size + Le16(archive, pos + 28);
    // With a data descriptor the sizes follow the data, so the walk cannot go on.
    if ((flags & kFlagDataDescriptor) != 0 && compressed_size == 0) break;
    if (compressed_size == kZip32Overflow) break;
    if (compressed_size > archive.size() - data_start) {
      return absl::DataLossError(absl::StrFormat(
          "truncated archive: member '%s' needs %d bytes of data but the file ends %d bytes "
          "into it",
          ShownValue(archive.substr(name_at, name_size)), compressed_size,
          archive.size() - data_start));
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

absl::Status ExplainNoArchive(absl::string_view archive) {
  if (LooksLikeNpy(archive)) {
    return absl::InvalidArgumentError(
        "this is a single .npy array, not an .npz archive (read it with ParseNpy)");
  }
  if (archive.size() < 4 || Le32(archive, 0) != kLocalHeaderSignature) {
    return absl::InvalidArgumentError(absl::StrCat(
        "not a zip archive (an .npz file is a zip of .npy members): it starts with \"",
        ShownValue(archive.substr(0, 8)), "\" and has no end-of-central-directory record"));
  }
  return ExplainTruncation(archive);
}

// ---------------------------------------------------------------------------------------------
// The zip container, through libzip.

struct ZipDiscard {
  void operator()(zip_t* zip) const { zip_discard(zip); }  // Read-only: nothing to write back.
};
using ZipArchive = std::unique_ptr<zip_t, ZipDiscard>;

struct ZipFileClose {
  void operator()(zip_file_t* file) const { zip_fclose(file); }
};
using ZipFile = std::unique_ptr<zip_file_t, ZipFileClose>;

// A libzip error as a status; `context` says what was being done.
absl::Status FromZipError(zip_error_t* error, absl::string_view context) {
  const std::string text = zip_error_strerror(error);
  switch (zip_error_code_zip(error)) {
    case ZIP_ER_MEMORY:
      return absl::ResourceExhaustedError(absl::StrCat(context, ": out of memory"));
    case ZIP_ER_MULTIDISK:
      return absl::UnimplementedError("multi-disk (split) zip archives are not supported");
    case ZIP_ER_ENCRNOTSUPP:
    case ZIP_ER_COMPNOTSUPP:
      return absl::UnimplementedError(absl::StrCat(context, ": ", text));
    default:
      return absl::DataLossError(absl::StrCat(context, ": ", text, "; the archive is damaged"));
  }
}

// libzip reads the archive in place: `archive` must outlive the returned handle.
absl::StatusOr<ZipArchive> OpenArchive(absl::string_view archive) {
  // libzip takes an empty buffer for an empty archive, which an empty file is not.
  if (archive.empty()) return absl::InvalidArgumentError("file is empty, not an .npz archive");
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* source = zip_source_buffer_create(archive.data(), archive.size(), /*freep=*/0, &error);
  zip_t* zip = source == nullptr ? nullptr : zip_open_from_source(source, ZIP_RDONLY, &error);
  absl::Status status = absl::OkStatus();
  if (zip == nullptr) {
    zip_source_free(source);  // Still ours when the open failed; null is fine.
    status = zip_error_code_zip(&error) == ZIP_ER_NOZIP ? ExplainNoArchive(archive)
                                                         : FromZipError(&error, "cannot open the zip archive");
  }
  zip_error_fini(&error);
  if (!status.ok()) return status;
  return ZipArchive(zip);
}

// What the central directory records for one member.
struct Member {
  zip_uint64_t index = 0;
  std::string name;  // As the archive spells it (no code page conversion), shown bounded.
  zip_stat_t stat;
};

absl::StatusOr<std::vector<Member>> ListMembers(zip_t* zip) {
  const zip_int64_t count = zip_get_num_entries(zip, 0);
  std::vector<Member> members;
  members.reserve(static_cast<size_t>(std::max<zip_int64_t>(count, 0)));
  constexpr zip_uint64_t kNeeded = ZIP_STAT_NAME | ZIP_STAT_SIZE | ZIP_STAT_COMP_SIZE |
                                   ZIP_STAT_CRC | ZIP_STAT_COMP_METHOD | ZIP_STAT_ENCRYPTION_METHOD;
  for (zip_int64_t i = 0; i < count; ++i) {
    Member member;
    member.index = static_cast<zip_uint64_t>(i);
    zip_stat_init(&member.stat);
    if (zip_stat_index(zip, member.index, ZIP_FL_ENC_RAW, &member.stat) != 0) {
      return FromZipError(zip_get_error(zip), absl::StrCat("central directory entry ", i));
    }
    if ((member.stat.valid & kNeeded) != kNeeded) {
      return absl::DataLossError(absl::StrCat("central directory entry ", i, " lacks its name or sizes"));
    }
    member.name = member.stat.name;
    members.push_back(std::move(member));
  }
  return members;
}

std::string MemberWhat(absl::string_view what, const Member& member) {
  return absl::StrCat(what, ": member '", ShownValue(member.name), "'");
}

// The sizes the archive records are checked before anything is inflated; ReadMember then
// refuses to produce more than the recorded size, so a bomb stops at the bound.
absl::Status CheckRecordedSizes(const std::vector<Member>& members, size_t archive_size,
                                absl::string_view what, const ResourceLimits& limits) {
  uint64_t total = 0;
  for (const Member& member : members) {
    // Data that cannot lie in the file is reported by ReadMember, before it inflates anything.
    if (member.stat.comp_size > archive_size) continue;
    if (member.stat.size > static_cast<uint64_t>(limits.max_npz_member_bytes)) {
      return absl::InvalidArgumentError(absl::StrCat(MemberWhat(what, member), ": inflates to ", member.stat.size,
                                                     " bytes, more than the limit of ", limits.max_npz_member_bytes,
                                                     " per member (max_npz_member_bytes)"));
    }
    total += member.stat.size;
    if (total > static_cast<uint64_t>(limits.max_decompressed_bytes)) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": members inflate to more than the limit of ",
                                                     limits.max_decompressed_bytes,
                                                     " bytes (max_decompressed_bytes)"));
    }
  }
  return absl::OkStatus();
}

// Only what NumPy writes: libzip would also inflate bzip2, xz and zstd, formats no .npz uses.
absl::Status CheckReadable(const zip_stat_t& stat, size_t archive_size) {
  if (stat.encryption_method != ZIP_EM_NONE) {
    return absl::UnimplementedError("member is encrypted, which is not supported");
  }
  if (stat.comp_method != ZIP_CM_STORE && stat.comp_method != ZIP_CM_DEFLATE) {
    return absl::UnimplementedError(absl::StrCat("compression method ", stat.comp_method,
                                                 " is not supported (only stored and deflate)"));
  }
  if (stat.comp_size > archive_size) {
    return absl::DataLossError(absl::StrCat("member data (", stat.comp_size,
                                            " bytes) runs past the end of the file (", archive_size,
                                            " bytes); the archive is truncated"));
  }
  if (stat.comp_method == ZIP_CM_STORE && stat.comp_size != stat.size) {
    return absl::DataLossError(absl::StrCat("stored (uncompressed) member records ", stat.comp_size,
                                            " bytes in the archive but ", stat.size, " bytes of content"));
  }
  return absl::OkStatus();
}

absl::Status CrcMismatch(uint32_t recorded, absl::string_view contents) {
  const uint32_t crc = static_cast<uint32_t>(
      crc32_z(0, reinterpret_cast<const Bytef*>(contents.data()), contents.size()));
  if (crc == recorded) return absl::OkStatus();
  return absl::DataLossError(absl::StrFormat(
      "CRC-32 mismatch: the archive records 0x%08x but the data hashes to 0x%08x; the file "
      "is corrupt",
      recorded, crc));
}

// Inflates at most `expected_size` + 1 bytes: one past the recorded size is enough to notice a
// member that inflates to more. The output grows as data arrives rather than being sized from
// the header up front, so a damaged size field cannot make us allocate for nothing.
absl::StatusOr<std::string> ReadBounded(zip_file_t* file, const zip_stat_t& stat) {
  constexpr uint64_t kChunk = uint64_t{1} << 20;
  const uint64_t expected_size = stat.size;
  std::string output;
  while (output.size() <= expected_size) {
    const size_t produced = output.size();
    const uint64_t room = std::min<uint64_t>(kChunk, expected_size + 1 - produced);
    output.resize(produced + room);
    const zip_int64_t read = zip_fread(file, &output[produced], room);
    if (read < 0) {
      output.resize(produced);
      zip_error_t* error = zip_file_get_error(file);
      // libzip checks the CRC-32 when the member ends; say which hashes differ.
      if (zip_error_code_zip(error) == ZIP_ER_CRC) return CrcMismatch(stat.crc, output);
      return FromZipError(error, stat.comp_method == ZIP_CM_STORE ? "cannot read" : "cannot inflate");
    }
    output.resize(produced + static_cast<size_t>(read));
    if (read == 0) break;
  }
  if (output.size() > expected_size) {
    return absl::DataLossError(
        absl::StrCat("inflates to more than the ", expected_size, " bytes the archive records"));
  }
  if (output.size() != expected_size) {
    return absl::DataLossError(absl::StrCat("inflates to ", output.size(),
                                            " bytes but the archive records ", expected_size));
  }
  return output;
}

absl::StatusOr<std::string> ReadMember(zip_t* zip, const Member& member, size_t archive_size) {
  if (absl::Status readable = CheckReadable(member.stat, archive_size); !readable.ok()) return readable;
  ZipFile file(zip_fopen_index(zip, member.index, 0));
  if (file == nullptr) return FromZipError(zip_get_error(zip), "cannot open");
  absl::StatusOr<std::string> contents = ReadBounded(file.get(), member.stat);
  if (!contents.ok()) return contents.status();
  // libzip checks the CRC too; checking here keeps the promise whatever path libzip took.
  if (absl::Status crc = CrcMismatch(member.stat.crc, *contents); !crc.ok()) return crc;
  return contents;
}

absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ParseNpzUnguarded(absl::string_view archive,
                                                                             absl::string_view what,
                                                                             const ResourceLimits& limits) {
  absl::StatusOr<ZipArchive> zip = OpenArchive(archive);
  if (!zip.ok()) return WithPrefix(zip.status(), what);
  absl::StatusOr<std::vector<Member>> members = ListMembers(zip->get());
  if (!members.ok()) return WithPrefix(members.status(), what);
  if (absl::Status sizes = CheckRecordedSizes(*members, archive.size(), what, limits); !sizes.ok()) return sizes;

  absl::flat_hash_map<std::string, NpyArray> arrays;
  for (const Member& member : *members) {
    if (absl::EndsWith(member.name, "/")) continue;  // A directory entry holds no data.
    const std::string member_what = MemberWhat(what, member);
    absl::StatusOr<std::string> contents = ReadMember(zip->get(), member, archive.size());
    if (!contents.ok()) return WithPrefix(contents.status(), member_what);
    absl::StatusOr<NpyArray> array = ParseNpy(*contents, member_what, limits);
    if (!array.ok()) return array.status();
    std::string key = member.name;
    if (absl::EndsWith(key, ".npy")) key.resize(key.size() - 4);
    if (!arrays.emplace(key, *std::move(array)).second) {
      return absl::InvalidArgumentError(
          absl::StrCat(member_what, ": the archive holds '", ShownValue(key), "' more than once"));
    }
  }
  return arrays;
}

}  // namespace

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
