// The PolicySpec a server's EnvSpec implies: what a learner records in the policy file it trains
// against that server (trackers, task policies and motor-skill families alike).
#ifndef MODSKILL_COMMON_WIRE_POLICY_SPEC_WIRE_H_
#define MODSKILL_COMMON_WIRE_POLICY_SPEC_WIRE_H_

#include "common/policy/policy_spec.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

// The spec of a policy for env `spec` (its task, reference frames and physics included), run with
// `action`; the caller sets what the env does not say (controller_input, a family's ranges).
PolicySpec PolicySpecOf(const v1::EnvSpec& spec, const ActionMapping& action);

}  // namespace modskill

#endif  // MODSKILL_COMMON_WIRE_POLICY_SPEC_WIRE_H_
