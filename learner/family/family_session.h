// The server session a motor-skill family lives in (SessionConfig.family): the one its trainer
// steps, and the one a family's policy.pt is described in. A family session's physics is its own
// (stable PD, no damping toward a warped clip's rate), not what the server's Describe reports, so
// a family file's physics record comes from such a session.
#ifndef MODSKILL_LEARNER_FAMILY_FAMILY_SESSION_H_
#define MODSKILL_LEARNER_FAMILY_FAMILY_SESSION_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "common/policy/family_parameters.h"
#include "common/policy/policy_spec.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner::family {

struct FamilySessionSettings {
  std::string clip;
  std::vector<ParamRange> ranges;
  int num_envs = 1;
  uint64_t seed = 0;
  double residual_scale = 0.3;
  double termination_distance = 0;  // 0: the server's family default
};

// Residual actions, no AMP observations, the family's clip over its ranges.
v1::SessionConfig FamilySessionConfig(const FamilySessionSettings& settings);

// The spec of a one-env session opened (and closed again) for `family`'s clip and ranges:
// what the server simulates that family in. INVALID_ARGUMENT when `family` is not a family's spec;
// the server's status (naming the field) when it cannot open such a session.
absl::StatusOr<v1::EnvSpec> DescribeFamilySession(SimulationClient& client, const PolicySpec& family);

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_FAMILY_SESSION_H_
