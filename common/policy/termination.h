// When training ends an episode early: how far a body may stray from its reference and which
// bodies are watched. Session configs, the learner's flags and its curriculum all name these, so
// the names and the bounds are defined once, here.
#ifndef MODSKILL_COMMON_POLICY_TERMINATION_H_
#define MODSKILL_COMMON_POLICY_TERMINATION_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

inline constexpr double kMaxTerminationDistance = 100;  // m
// A termination distance in (0, kMaxTerminationDistance] m.
absl::Status ValidateTerminationDistance(double distance);

// Which bodies training termination watches.
enum class TerminationBodies {
  kAll,
  kNoFeet,  // every body but the ankles and toes (PHC): feet slip without the character falling
};

// "all" / "no_feet": the names flags, configs and Describe use.
absl::StatusOr<TerminationBodies> ParseTerminationBodies(absl::string_view name);
std::vector<std::string> TerminationBodiesNames();

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_TERMINATION_H_
