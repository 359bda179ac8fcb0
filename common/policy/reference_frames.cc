#include "common/policy/reference_frames.h"

#include "absl/strings/str_cat.h"

namespace modskill {

absl::Status ValidateReferenceFrames(int frames, absl::string_view field) {
  if (frames < 1 || frames > kMaxReferenceFrames) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": ", frames, " is not in [1, ", kMaxReferenceFrames, "] reference frames"));
  }
  return absl::OkStatus();
}

}  // namespace modskill
