// The policy enums (common/policy) and their proto twins, mapped in one place for the service,
// the learner and the tools. Unspecified proto values mean the default (absolute actions, all
// bodies); a value this build does not know is an InvalidArgument naming the field.
#ifndef MODSKILL_COMMON_WIRE_POLICY_ENUMS_H_
#define MODSKILL_COMMON_WIRE_POLICY_ENUMS_H_

#include "absl/status/statusor.h"
#include "common/policy/action_mode.h"
#include "common/policy/termination.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

v1::ActionMode ToWire(ActionMode mode);
v1::TerminationBodies ToWire(TerminationBodies bodies);

absl::StatusOr<ActionMode> ActionModeFromWire(v1::ActionMode mode);
absl::StatusOr<TerminationBodies> TerminationBodiesFromWire(v1::TerminationBodies bodies);

}  // namespace modskill

#endif  // MODSKILL_COMMON_WIRE_POLICY_ENUMS_H_
