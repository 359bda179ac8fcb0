#include "common/shown_value.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace modskill {

std::string ShownValue(absl::string_view value) {
  std::string shown;
  for (char c : value.substr(0, kMaxShownValueBytes)) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F) {
      shown.push_back(c);
    } else {
      absl::StrAppendFormat(&shown, "\\x%02x", u);
    }
  }
  if (value.size() > kMaxShownValueBytes) absl::StrAppend(&shown, "... (", value.size(), " bytes)");
  return shown;
}

}  // namespace modskill
