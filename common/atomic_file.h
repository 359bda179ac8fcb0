// Writes a file so that readers see either the old or the complete new content, never a torn one.
#ifndef MODSKILL_COMMON_ATOMIC_FILE_H_
#define MODSKILL_COMMON_ATOMIC_FILE_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

// Writes to "<path>.tmp.<pid>", fsyncs it, renames it over `path` and fsyncs the directory.
absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents);

absl::StatusOr<std::string> ReadFileToString(const std::string& path, size_t max_bytes);

}  // namespace modskill

#endif  // MODSKILL_COMMON_ATOMIC_FILE_H_
