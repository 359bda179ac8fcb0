// How a message shows a value a client or a file chose (a clip name, a session id, a layout
// name): bounded and escaped, so that no input can make an error message huge or unprintable.
#ifndef MODSKILL_COMMON_SHOWN_VALUE_H_
#define MODSKILL_COMMON_SHOWN_VALUE_H_

#include <cstddef>
#include <string>

#include "absl/strings/string_view.h"

namespace modskill {

inline constexpr size_t kMaxShownValueBytes = 64;

// The first kMaxShownValueBytes bytes of `value`, control and non-ASCII bytes as \xNN, and
// "... (N bytes)" when it was longer.
std::string ShownValue(absl::string_view value);

}  // namespace modskill

#endif  // MODSKILL_COMMON_SHOWN_VALUE_H_
