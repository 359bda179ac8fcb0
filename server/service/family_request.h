// The task parameters a of a request that runs or queries a motor-skill family's policy
// (RolloutRequest.family_params, QueryFamilyRequest.params): by name against the checkpoint's
// trained ranges, each left out at its range's middle, nothing clamped.
#ifndef MODSKILL_SERVER_SERVICE_FAMILY_REQUEST_H_
#define MODSKILL_SERVER_SERVICE_FAMILY_REQUEST_H_

#include <string>
#include <vector>

#include <google/protobuf/map.h>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/family_parameters.h"

namespace modskill {

// a in range order. INVALID_ARGUMENT naming `field`[name] for a name the ranges do not hold, a
// non-finite value or one outside its trained range.
absl::StatusOr<std::vector<double>> ResolveFamilyParams(const std::vector<ParamRange>& ranges,
                                                        const google::protobuf::Map<std::string, double>& given,
                                                        absl::string_view field);

// a as the wire's name -> value map.
void SetFamilyParams(const std::vector<ParamRange>& ranges, const std::vector<double>& a,
                     google::protobuf::Map<std::string, double>* out);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_FAMILY_REQUEST_H_
