// Reader for NumPy .npz archives (a zip of .npy members), such as AMASS motion files.
// Self-contained: parses the zip container and the .npy format itself, with zlib for
// inflate and CRC-32, so that loading motions needs no Python.
#ifndef MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_
#define MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/resource_limits.h"

namespace modskill {

// One array from a .npy member.
struct NpyArray {
  // Row-major (C order) after conversion, even when the file was written in Fortran order.
  // Empty for a 0-d array.
  std::vector<int64_t> shape;
  // Numeric arrays (f4 f8 i1 i2 i4 i8 u1 u2 u4 u8 b1, either byte order) converted to double.
  // 64-bit integers beyond 2^53 lose precision. Empty for string arrays.
  std::vector<double> data;
  // For '<U' / '|S' string arrays: the first element as UTF-8 (or the raw bytes for 'S'),
  // trailing NULs stripped, e.g. AMASS 'gender'. Empty for numeric arrays.
  std::string text;
  // The descr exactly as written in the header, e.g. "<f4".
  std::string dtype;

  // Number of elements: the product of shape, 1 for a 0-d array.
  int64_t size() const;
};

// Reads every member of the archive at `path`, keyed by member name without the ".npy"
// suffix. Checks the CRC-32 of each member. Every failure, including a missing file, is a
// non-OK status whose message names the path and, where it applies, the member.
// Sizes are bounded by `limits` before anything is inflated or allocated: the sizes the zip
// records for each member (max_npz_member_bytes) and for all of them together
// (max_decompressed_bytes), and each array as doubles (max_npz_member_bytes); the file itself may
// be no larger than max_decompressed_bytes. Breaking a bound is InvalidArgument.
absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ReadNpz(
    const std::string& path, const ResourceLimits& limits = DefaultResourceLimits());

// The same for the archive's bytes in memory; `what` names it in messages.
absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ParseNpz(
    absl::string_view archive, absl::string_view what, const ResourceLimits& limits = DefaultResourceLimits());

// Parses the bytes of one .npy file (format versions 1.0, 2.0 and 3.0). `what` prefixes
// every error message, e.g. "walk.npz: member 'poses.npy'".
absl::StatusOr<NpyArray> ParseNpy(absl::string_view bytes, absl::string_view what,
                                  const ResourceLimits& limits = DefaultResourceLimits());

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_
