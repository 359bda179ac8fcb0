// Reader for NumPy .npz archives (a zip of .npy members), such as AMASS motion files. libzip reads
// the zip container (zip64, stored and deflated members, CRC-32); npy_reader.h parses each member.
// This file bounds what libzip may inflate and turns its errors into statuses that name the
// archive and the member.
#ifndef MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_
#define MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_

#include <string>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/npy_reader.h"
#include "server/core/motion/resource_limits.h"

namespace modskill {

// Reads every member of the archive at `path`, keyed by member name without the ".npy"
// suffix. Checks the CRC-32 of each member. Every failure, including a missing file, is a
// non-OK status whose message names the path and, where it applies, the member.
// Sizes are bounded by `limits` before anything is inflated or allocated: the sizes the zip
// records for each member (max_npz_member_bytes) and for all of them together
// (max_decompressed_bytes), and each array as doubles (max_npz_member_bytes); the file itself may
// be no larger than max_decompressed_bytes. No member is inflated past the size it records.
// Breaking a bound is InvalidArgument.
absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ReadNpz(
    const std::string& path, const ResourceLimits& limits = DefaultResourceLimits());

// The same for the archive's bytes in memory; `what` names it in messages.
absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ParseNpz(
    absl::string_view archive, absl::string_view what, const ResourceLimits& limits = DefaultResourceLimits());

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_NPZ_READER_H_
