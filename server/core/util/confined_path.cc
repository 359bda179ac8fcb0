#include "server/core/util/confined_path.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

// Whether `path` (absolute, normalized) lies strictly under `base` (absolute, normalized).
bool IsUnder(const std::filesystem::path& path, const std::filesystem::path& base) {
  const auto [base_end, path_at] = std::mismatch(base.begin(), base.end(), path.begin(), path.end());
  return base_end == base.end() && path_at != path.end();
}

// A directory as paths are compared against it: absolute, links resolved, no trailing "/"
// ("dir/" resolves with an empty last part). Empty when it cannot be resolved.
std::filesystem::path ResolvedDirectory(const std::string& directory) {
  std::error_code error;
  std::filesystem::path base = std::filesystem::weakly_canonical(std::filesystem::absolute(directory, error), error);
  if (error) return {};
  if (!base.has_filename()) base = base.parent_path();
  return base;
}

}  // namespace

absl::StatusOr<std::string> ConfinedPath(const std::string& directory, absl::string_view file_name) {
  namespace fs = std::filesystem;
  const std::string name(file_name);
  const fs::path relative(name);
  if (name.empty() || relative.has_root_path() || relative.filename() != relative || name == "." || name == "..") {
    return absl::InvalidArgumentError(absl::StrCat("'", name, "' is not a plain file name (directory ", directory, ")"));
  }
  std::error_code error;
  const fs::path base = ResolvedDirectory(directory);
  if (base.empty()) return absl::InvalidArgumentError(absl::StrCat(directory, ": cannot resolve"));
  // A link that dangles is not resolved by weakly_canonical: refuse links outright.
  if (fs::is_symlink(fs::symlink_status(base / relative, error))) {
    return absl::InvalidArgumentError(absl::StrCat("'", name, "' is a symbolic link in ", base.string()));
  }
  const fs::path resolved = fs::weakly_canonical(base / relative, error);
  if (error) return absl::InvalidArgumentError(absl::StrCat(name, ": cannot resolve under ", directory, ": ", error.message()));
  if (!IsUnder(resolved, base)) {
    return absl::InvalidArgumentError(
        absl::StrCat("'", name, "' resolves to ", resolved.string(), ", outside ", base.string()));
  }
  return resolved.string();
}

absl::StatusOr<std::string> ReadConfinedFile(const std::vector<std::string>& directories, const std::string& path,
                                             int64_t max_bytes, absl::string_view field) {
  namespace fs = std::filesystem;
  const absl::Status outside = absl::PermissionDeniedError(absl::StrCat(
      field, ": the server reads checkpoint files only in its --checkpoint_dir directories",
      directories.empty() ? " (none configured: send the file's bytes instead)" : ""));
  if (path.empty()) return absl::InvalidArgumentError(absl::StrCat(field, ": empty"));
  // Lexically first, before touching the file: a path outside every directory is refused
  // whether or not it exists.
  std::vector<std::pair<fs::path, fs::path>> candidates;  // (file, its directory)
  for (const std::string& directory : directories) {
    const fs::path base = ResolvedDirectory(directory);
    if (base.empty()) continue;
    const fs::path file = (fs::path(path).is_absolute() ? fs::path(path) : base / path).lexically_normal();
    if (IsUnder(file, base)) candidates.emplace_back(file, base);
  }
  if (candidates.empty()) return outside;
  for (const auto& [file, base] : candidates) {
    // Non-blocking, so that a FIFO cannot hang the call; the descriptor then names the real file.
    const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
      if (errno == ENOENT || errno == ENOTDIR) continue;
      return absl::PermissionDeniedError(absl::StrCat(field, ": cannot open: ", std::strerror(errno)));
    }
    struct FdCloser {
      int fd;
      ~FdCloser() { ::close(fd); }
    } closer{fd};
    std::error_code error;
    const fs::path real = fs::read_symlink(absl::StrCat("/proc/self/fd/", fd), error);
    if (error || !IsUnder(real, base)) return outside;  // a link out of the directory
    struct stat info;
    if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
      return absl::InvalidArgumentError(absl::StrCat(field, ": not a regular file"));
    }
    if (info.st_size > max_bytes) {
      return absl::ResourceExhaustedError(
          absl::StrCat(field, ": ", info.st_size, " bytes, more than the limit of ", max_bytes));
    }
    std::string bytes(static_cast<size_t>(info.st_size), '\0');
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t got = ::read(fd, bytes.data() + done, bytes.size() - done);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return absl::DataLossError(absl::StrCat(field, ": read failed after ", done, " bytes"));
      done += static_cast<size_t>(got);
    }
    return bytes;
  }
  return absl::NotFoundError(absl::StrCat(field, ": no such file in the --checkpoint_dir directories"));
}

}  // namespace modskill
