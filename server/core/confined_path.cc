#include "server/core/confined_path.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace modskill {

absl::StatusOr<std::string> ConfinedPath(const std::string& directory, absl::string_view file_name) {
  namespace fs = std::filesystem;
  const std::string name(file_name);
  const fs::path relative(name);
  if (name.empty() || relative.has_root_path() || relative.filename() != relative || name == "." || name == "..") {
    return absl::InvalidArgumentError(absl::StrCat("'", name, "' is not a plain file name (directory ", directory, ")"));
  }
  std::error_code error;
  fs::path base = fs::weakly_canonical(fs::absolute(directory, error), error);
  if (error) return absl::InvalidArgumentError(absl::StrCat(directory, ": cannot resolve: ", error.message()));
  if (!base.has_filename()) base = base.parent_path();  // "dir/" resolves with an empty last part
  // A link that dangles is not resolved by weakly_canonical: refuse links outright.
  if (fs::is_symlink(fs::symlink_status(base / relative, error))) {
    return absl::InvalidArgumentError(absl::StrCat("'", name, "' is a symbolic link in ", base.string()));
  }
  const fs::path resolved = fs::weakly_canonical(base / relative, error);
  if (error) return absl::InvalidArgumentError(absl::StrCat(name, ": cannot resolve under ", directory, ": ", error.message()));
  // Under `base`: its components are a prefix of the resolved path's, and something follows.
  const auto [base_end, resolved_at] = std::mismatch(base.begin(), base.end(), resolved.begin(), resolved.end());
  if (base_end != base.end() || resolved_at == resolved.end()) {
    return absl::InvalidArgumentError(
        absl::StrCat("'", name, "' resolves to ", resolved.string(), ", outside ", base.string()));
  }
  return resolved.string();
}

}  // namespace modskill
