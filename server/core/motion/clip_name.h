// Clip names become file names (the library, --save_generated, modskill-motion import), so a
// name is checked wherever one enters: letters, digits and `_ - . ~` only, no leading dot (so
// no "." / ".." / hidden files), no "..", at most a bounded length. Generated variants append
// "~<part>~<n>", which stays within these rules.
#ifndef MODSKILL_SERVER_CORE_MOTION_CLIP_NAME_H_
#define MODSKILL_SERVER_CORE_MOTION_CLIP_NAME_H_

#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace modskill {

// InvalidArgument naming `field` (e.g. "name") when `name` breaks a rule above or is longer than
// `max_length`. The message shows at most the first 64 characters, escaped.
absl::Status ValidateClipName(absl::string_view name, int max_length, absl::string_view field = "name");

// A valid name from a file stem: disallowed characters become '_', a leading dot is dropped, the
// length is cut to `max_length`; "clip" when nothing is left.
std::string SanitizeClipName(absl::string_view stem, int max_length);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_CLIP_NAME_H_
