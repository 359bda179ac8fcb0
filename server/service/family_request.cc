#include "server/service/family_request.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/shown_value.h"

namespace modskill {

absl::StatusOr<std::vector<double>> ResolveFamilyParams(const std::vector<ParamRange>& ranges,
                                                        const google::protobuf::Map<std::string, double>& given,
                                                        absl::string_view field) {
  std::vector<std::string> names;
  for (const ParamRange& range : ranges) names.push_back(range.name);
  for (const auto& [name, value] : given) {
    bool known = false;
    for (const ParamRange& range : ranges) known |= range.name == name;
    if (!known) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", ShownValue(name), "]: the checkpoint's family varies ",
                                                     absl::StrJoin(names, ", "), " only"));
    }
  }
  std::vector<double> a;
  for (const ParamRange& range : ranges) {
    auto it = given.find(range.name);
    if (it == given.end()) {
      a.push_back(0.5 * (range.lo + range.hi));
      continue;
    }
    const double value = it->second;
    if (!std::isfinite(value) || value < range.lo || value > range.hi) {
      return absl::InvalidArgumentError(absl::StrCat(field, "[", range.name, "]: ", value, " is outside the trained range [",
                                                     range.lo, ", ", range.hi, "]"));
    }
    a.push_back(value);
  }
  return a;
}

void SetFamilyParams(const std::vector<ParamRange>& ranges, const std::vector<double>& a,
                     google::protobuf::Map<std::string, double>* out) {
  for (size_t k = 0; k < ranges.size() && k < a.size(); ++k) (*out)[ranges[k].name] = a[k];
}

}  // namespace modskill
