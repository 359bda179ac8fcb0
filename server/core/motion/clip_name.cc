#include "server/core/motion/clip_name.h"

#include <algorithm>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/shown_value.h"

namespace modskill {
namespace {

bool AllowedChar(char c) {
  return absl::ascii_isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '~';
}

}  // namespace

absl::Status ValidateClipName(absl::string_view name, int max_length, absl::string_view field) {
  auto bad = [&](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(field, " '", ShownValue(name), "': ", why));
  };
  if (name.empty()) return absl::InvalidArgumentError(absl::StrCat(field, ": empty clip name"));
  if (name.size() > static_cast<size_t>(max_length)) {
    return bad(absl::StrCat(name.size(), " characters, more than the limit of ", max_length, " (max_name_length)"));
  }
  for (char c : name) {
    if (!AllowedChar(c)) return bad("only letters, digits and _ - . ~ are allowed in a clip name");
  }
  if (name.front() == '.') return bad("a clip name must not start with '.'");
  if (absl::StrContains(name, "..")) return bad("a clip name must not contain '..'");
  return absl::OkStatus();
}

std::string SanitizeClipName(absl::string_view stem, int max_length) {
  std::string name;
  for (char c : stem) {
    // Dots in a row would spell "..": keep only the first.
    if (c == '.' && (name.empty() || name.back() == '.')) continue;
    name.push_back(AllowedChar(c) ? c : '_');
  }
  name.resize(std::min(name.size(), static_cast<size_t>(std::max(max_length, 1))));
  if (name.empty()) name = "clip";
  return name;
}

}  // namespace modskill
