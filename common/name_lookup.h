// Where each name of a list sits among the names a thing knows, for the flags and fields that
// name parts (SessionConfig.reward_parts, --train_parts, modskill-motion splice --parts): every
// name must be known and given once, and an error names the entry and lists what is known.
#ifndef MODSKILL_COMMON_NAME_LOOKUP_H_
#define MODSKILL_COMMON_NAME_LOOKUP_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

// The index in `known` of each of `names`, in their order. INVALID_ARGUMENT
// "FIELD[i]: 'NAME' is not KNOWN_AS (a, b, ...)" for an unknown name, "FIELD[i]: 'NAME' is given
// twice" for a repeated one; names are shown bounded (ShownValue).
absl::StatusOr<std::vector<int>> IndicesOfNames(const std::vector<std::string>& names,
                                                const std::vector<std::string>& known, absl::string_view field,
                                                absl::string_view known_as);

}  // namespace modskill

#endif  // MODSKILL_COMMON_NAME_LOOKUP_H_
