// Paths built from names a client or a file chose (clip names) must stay inside the directory
// the operator configured: the joined path is resolved (symbolic links, "..") and checked to lie
// under the resolved directory, so no name can write elsewhere even if a check upstream missed it.
#ifndef MODSKILL_SERVER_CORE_UTIL_CONFINED_PATH_H_
#define MODSKILL_SERVER_CORE_UTIL_CONFINED_PATH_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

// Longest file name common file systems take (NAME_MAX).
inline constexpr int kMaxFileNameLength = 255;

// `directory`/`file_name`, resolved; InvalidArgument when `file_name` is not one plain file name
// or the result would lie outside `directory` (which need not exist yet), or when it names a
// symbolic link.
absl::StatusOr<std::string> ConfinedPath(const std::string& directory, absl::string_view file_name);

// Reads the regular file `path` (absolute, or relative to each of `directories` in turn) when it
// lies in one of `directories` once links are resolved, and is at most `max_bytes` long. The
// answer for a path outside them is PermissionDenied, the same whether the file exists or not,
// so that a client cannot probe the rest of the file system; NotFound only for a file missing
// inside them. Messages start with `field`. No directories: every path is PermissionDenied.
absl::StatusOr<std::string> ReadConfinedFile(const std::vector<std::string>& directories, const std::string& path,
                                             int64_t max_bytes, absl::string_view field);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_UTIL_CONFINED_PATH_H_
