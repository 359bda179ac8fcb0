#include "client/cpp/cli_output.h"

#include <cstdio>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace modskill::cli {

int Fail(const absl::Status& status) {
  std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
  return kRuntimeError;
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return kRuntimeError;
}

std::string FormatBytes(size_t bytes) {
  if (bytes < 1024) return absl::StrCat(bytes, " B");
  if (bytes < (size_t{1} << 20)) return absl::StrFormat("%.1f KiB (%d B)", bytes / 1024.0, bytes);
  return absl::StrFormat("%.1f MiB (%d B)", bytes / 1048576.0, bytes);
}

}  // namespace modskill::cli
