// The task parameters a of a motor-skill family (Lee et al. 2021; DESIGN.md section 4): the
// names the server's parameterized envs offer, and a run's ranges over them. The server and the
// learner both check a request against this one catalog.
#ifndef MODSKILL_COMMON_POLICY_FAMILY_PARAMETERS_H_
#define MODSKILL_COMMON_POLICY_FAMILY_PARAMETERS_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/types/span.h"

namespace modskill {

// One parameter the server can vary per episode.
struct FamilyParameterInfo {
  const char* name;
  const char* unit;         // "" for a dimensionless scale
  const char* description;
  std::optional<double> default_value;  // nullopt: the clip's own value (a jump's height, ...)
  double min_value;         // physical floor of any range
  bool min_exclusive;       // a scale must stay > 0, a height may be 0
};

// Every parameter the server will offer, in a fixed order.
absl::Span<const FamilyParameterInfo> FamilyParameterCatalog();
// The catalog entry called `name`, or nullptr.
const FamilyParameterInfo* FindFamilyParameter(absl::string_view name);

// The range a run samples one parameter over. lo == hi makes it a constraint (DESIGN.md: a
// zero-range parameter is a constraint), which is allowed.
struct ParamRange {
  std::string name;
  double lo = 0;
  double hi = 0;
};

// "name=lo:hi" (a range) or "name=v" (a constraint, lo = hi = v), as `--param gravity=4:14`.
// INVALID_ARGUMENT, naming the parameter, for a malformed string, an unknown name, a
// non-finite or inverted range, or one below the parameter's physical floor.
absl::StatusOr<ParamRange> ParseParamRange(absl::string_view text);
// Every string parsed, plus: a name given twice is INVALID_ARGUMENT.
absl::StatusOr<std::vector<ParamRange>> ParseParamRanges(absl::Span<const std::string> texts);
// The same checks for a range built in code (or decoded from the wire).
absl::Status ValidateParamRange(const ParamRange& range);

// How much `leg_scale` and `arm_scale` stretch one body (lengths and radii alike): the legs from
// the hips down (thighs, shins, feet, toes) take leg_scale, the arms from the shoulders out
// (upper arms, forearms, wrists, hands) arm_scale, every other body 1. The server scales its
// model by it (server/core/env/family_body_models.h), the viewer the limbs it draws.
double FamilyLimbScale(absl::string_view body, double leg_scale, double arm_scale);

// A run's parameter space: its ranges, and the map to the unit cube the elite set, the
// parameterization network and the curriculum measure distances in. Every dimension is
// normalized to [0, 1] over its range so that gravity (m/s^2) and a scale weigh alike in
// r = 0.1 and sigma_k = 0.28; a zero-width dimension maps to 0.
class ParamSpace {
 public:
  // INVALID_ARGUMENT for an empty set, an invalid range or a duplicate name.
  static absl::StatusOr<ParamSpace> Create(std::vector<ParamRange> ranges);

  int dims() const { return static_cast<int>(ranges_.size()); }
  const std::vector<ParamRange>& ranges() const { return ranges_; }
  bool is_constraint(int dim) const { return ranges_[dim].hi == ranges_[dim].lo; }

  // (a - lo) / (hi - lo) per dimension, 0 where hi == lo. INVALID_ARGUMENT naming the
  // parameter for a wrong size or a value outside its range.
  absl::StatusOr<std::vector<double>> Normalize(absl::Span<const double> a) const;
  // lo + u (hi - lo); u is clamped to [0, 1]. INVALID_ARGUMENT for a wrong size or a NaN.
  absl::StatusOr<std::vector<double>> Denormalize(absl::Span<const double> u) const;

 private:
  explicit ParamSpace(std::vector<ParamRange> ranges) : ranges_(std::move(ranges)) {}
  std::vector<ParamRange> ranges_;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_FAMILY_PARAMETERS_H_
