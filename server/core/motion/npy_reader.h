// Reader for one NumPy .npy array (format versions 1.0, 2.0 and 3.0): the header dict, the dtypes
// motion files use, C and Fortran order. The project's own parser, so that loading motions needs
// no Python; npz_reader.h reads the zip around such arrays.
#ifndef MODSKILL_SERVER_CORE_MOTION_NPY_READER_H_
#define MODSKILL_SERVER_CORE_MOTION_NPY_READER_H_

#include <cstdint>
#include <string>
#include <vector>

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

// True when `bytes` start with the .npy magic "\x93NUMPY".
bool LooksLikeNpy(absl::string_view bytes);

// Parses the bytes of one .npy file. `what` prefixes every error message, e.g.
// "walk.npz: member 'poses.npy'". Matrices with more rows than max_clip_frames, and numeric
// arrays larger than max_npz_member_bytes as doubles, are InvalidArgument before any allocation.
absl::StatusOr<NpyArray> ParseNpy(absl::string_view bytes, absl::string_view what,
                                  const ResourceLimits& limits = DefaultResourceLimits());

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_NPY_READER_H_
