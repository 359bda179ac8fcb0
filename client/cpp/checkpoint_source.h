// How a command hands its --checkpoint to the server (Rollout, QueryFamily): with --upload the
// local file's bytes, otherwise its absolute path, which the server reads from its
// --checkpoint_dir directories.
#ifndef MODSKILL_CLIENT_CPP_CHECKPOINT_SOURCE_H_
#define MODSKILL_CLIENT_CPP_CHECKPOINT_SOURCE_H_

#include <filesystem>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"

namespace modskill::cli {

inline constexpr size_t kMaxCheckpointUpload = size_t{512} << 20;

// Sets `request`'s checkpoint_bytes or checkpoint_path; `shown` is how the output names it.
template <typename Request>
absl::Status SetCheckpoint(const std::string& checkpoint, bool upload, Request* request, std::string* shown) {
  *shown = checkpoint;
  if (upload) {
    auto bytes = ReadFileToString(checkpoint, kMaxCheckpointUpload);
    if (!bytes.ok()) return absl::Status(bytes.status().code(), absl::StrCat("--checkpoint: ", bytes.status().message()));
    request->set_checkpoint_bytes(*std::move(bytes));
    return absl::OkStatus();
  }
  std::error_code error;
  const std::filesystem::path path = std::filesystem::absolute(checkpoint, error);
  *shown = error ? checkpoint : path.lexically_normal().string();
  request->set_checkpoint_path(*shown);
  return absl::OkStatus();
}

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_CHECKPOINT_SOURCE_H_
