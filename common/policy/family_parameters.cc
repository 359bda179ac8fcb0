#include "common/policy/family_parameters.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace modskill {
namespace {

constexpr FamilyParameterInfo kCatalog[] = {
    {"gravity", "m/s^2", "magnitude of gravity", 9.81, 0, false},
    {"leg_scale", "", "length and radius scale of both legs' bodies", 1.0, 0, true},
    {"arm_scale", "", "length and radius scale of both arms' bodies", 1.0, 0, true},
    {"body_mass_scale", "", "scale of every body's mass", 1.0, 0, true},
    {"jump_height", "m", "height the root must clear at the top of a jump", std::nullopt, 0, false},
    {"target_height", "m", "height of the target a hand or foot must reach", std::nullopt, 0, false},
    {"obstacle_height", "m", "height of the obstacle in the path", std::nullopt, 0, false},
    {"obstacle_distance", "m", "distance from the start to the obstacle", std::nullopt, 0, false},
};

std::string CatalogNames() {
  std::vector<std::string> names;
  for (const FamilyParameterInfo& info : kCatalog) names.push_back(info.name);
  return absl::StrJoin(names, ", ");
}

absl::StatusOr<double> ParseNumber(absl::string_view name, absl::string_view text) {
  double value = 0;
  if (!absl::SimpleAtod(absl::StripAsciiWhitespace(text), &value)) {
    return absl::InvalidArgumentError(
        absl::StrCat("param ", name, ": '", text.substr(0, 32), "' is not a number"));
  }
  return value;
}

}  // namespace

absl::Span<const FamilyParameterInfo> FamilyParameterCatalog() { return kCatalog; }

const FamilyParameterInfo* FindFamilyParameter(absl::string_view name) {
  for (const FamilyParameterInfo& info : kCatalog) {
    if (name == info.name) return &info;
  }
  return nullptr;
}

absl::Status ValidateParamRange(const ParamRange& range) {
  const FamilyParameterInfo* info = FindFamilyParameter(range.name);
  if (info == nullptr) {
    return absl::InvalidArgumentError(absl::StrCat("param '", range.name.substr(0, 64),
                                                   "' is not a family parameter (one of ", CatalogNames(), ")"));
  }
  if (!std::isfinite(range.lo) || !std::isfinite(range.hi)) {
    return absl::InvalidArgumentError(
        absl::StrCat("param ", range.name, ": range ", range.lo, ":", range.hi, " is not finite"));
  }
  if (range.lo > range.hi) {
    return absl::InvalidArgumentError(
        absl::StrCat("param ", range.name, ": range ", range.lo, ":", range.hi, " is inverted (lo > hi)"));
  }
  if (range.lo < info->min_value || (info->min_exclusive && range.lo == info->min_value)) {
    return absl::InvalidArgumentError(absl::StrCat("param ", range.name, ": lo ", range.lo, " must be ",
                                                   info->min_exclusive ? "> " : ">= ", info->min_value));
  }
  return absl::OkStatus();
}

absl::StatusOr<ParamRange> ParseParamRange(absl::string_view text) {
  const std::pair<absl::string_view, absl::string_view> name_value = absl::StrSplit(text, absl::MaxSplits('=', 1));
  ParamRange range;
  range.name = std::string(absl::StripAsciiWhitespace(name_value.first));
  if (range.name.empty() || !absl::StrContains(text, '=')) {
    return absl::InvalidArgumentError(
        absl::StrCat("param '", text.substr(0, 64), "' is not name=lo:hi or name=value"));
  }
  const std::vector<absl::string_view> bounds = absl::StrSplit(name_value.second, ':');
  if (bounds.size() > 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("param ", range.name, ": '", name_value.second.substr(0, 64), "' is not lo:hi or value"));
  }
  absl::StatusOr<double> lo = ParseNumber(range.name, bounds.front());
  if (!lo.ok()) return lo.status();
  absl::StatusOr<double> hi = ParseNumber(range.name, bounds.back());
  if (!hi.ok()) return hi.status();
  range.lo = *lo;
  range.hi = *hi;
  if (absl::Status valid = ValidateParamRange(range); !valid.ok()) return valid;
  return range;
}

absl::StatusOr<std::vector<ParamRange>> ParseParamRanges(absl::Span<const std::string> texts) {
  std::vector<ParamRange> ranges;
  std::set<std::string> seen;
  for (const std::string& text : texts) {
    absl::StatusOr<ParamRange> range = ParseParamRange(text);
    if (!range.ok()) return range.status();
    if (!seen.insert(range->name).second) {
      return absl::InvalidArgumentError(absl::StrCat("param ", range->name, " is given twice"));
    }
    ranges.push_back(*std::move(range));
  }
  return ranges;
}

absl::StatusOr<ParamSpace> ParamSpace::Create(std::vector<ParamRange> ranges) {
  if (ranges.empty()) return absl::InvalidArgumentError("param space: no parameter ranges");
  std::set<std::string> seen;
  for (const ParamRange& range : ranges) {
    if (absl::Status valid = ValidateParamRange(range); !valid.ok()) return valid;
    if (!seen.insert(range.name).second) {
      return absl::InvalidArgumentError(absl::StrCat("param ", range.name, " is given twice"));
    }
  }
  return ParamSpace(std::move(ranges));
}

absl::StatusOr<std::vector<double>> ParamSpace::Normalize(absl::Span<const double> a) const {
  if (a.size() != ranges_.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("param vector has ", a.size(), " values, the space ", ranges_.size(), " parameters"));
  }
  std::vector<double> u(a.size());
  for (size_t i = 0; i < a.size(); ++i) {
    const ParamRange& range = ranges_[i];
    if (!(a[i] >= range.lo && a[i] <= range.hi)) {
      return absl::InvalidArgumentError(
          absl::StrCat("param ", range.name, ": ", a[i], " is outside ", range.lo, ":", range.hi));
    }
    u[i] = range.hi > range.lo ? (a[i] - range.lo) / (range.hi - range.lo) : 0.0;
  }
  return u;
}

absl::StatusOr<std::vector<double>> ParamSpace::Denormalize(absl::Span<const double> u) const {
  if (u.size() != ranges_.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("normalized param vector has ", u.size(), " values, the space ", ranges_.size(), " parameters"));
  }
  std::vector<double> a(u.size());
  for (size_t i = 0; i < u.size(); ++i) {
    const ParamRange& range = ranges_[i];
    if (std::isnan(u[i])) return absl::InvalidArgumentError(absl::StrCat("param ", range.name, ": normalized value is NaN"));
    a[i] = range.lo + std::clamp(u[i], 0.0, 1.0) * (range.hi - range.lo);
  }
  return a;
}

double FamilyLimbScale(absl::string_view body, double leg_scale, double arm_scale) {
  for (const char* leg : {"Hip", "Knee", "Ankle", "Toe"}) {
    if (absl::StrContains(body, leg)) return leg_scale;
  }
  for (const char* arm : {"Shoulder", "Elbow", "Wrist", "Hand"}) {
    if (absl::StrContains(body, arm)) return arm_scale;
  }
  return 1.0;
}

}  // namespace modskill
