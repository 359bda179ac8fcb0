#include "common/name_lookup.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/shown_value.h"

namespace modskill {

absl::StatusOr<std::vector<int>> IndicesOfNames(const std::vector<std::string>& names,
                                                const std::vector<std::string>& known, absl::string_view field,
                                                absl::string_view known_as) {
  std::vector<int> indices;
  for (size_t i = 0; i < names.size(); ++i) {
    const auto found = std::find(known.begin(), known.end(), names[i]);
    if (found == known.end()) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", i, "]: '", ShownValue(names[i]), "' is not ", known_as,
                                                     " (", absl::StrJoin(known, ", "), ")"));
    }
    const int index = static_cast<int>(found - known.begin());
    if (std::find(indices.begin(), indices.end(), index) != indices.end()) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", i, "]: '", ShownValue(names[i]), "' is given twice"));
    }
    indices.push_back(index);
  }
  return indices;
}

}  // namespace modskill
