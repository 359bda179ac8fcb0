// Exports a motor-skill family (Lee et al. 2021; issue 14) as one policy.pt the server runs like
// any policy (common/policy/policy_checkpoint.h): forward(obs) maps RAW family observations
// (tracking's features, then a normalized over the trained ranges and the phase) to the policy's
// mean actions (hinge displacements, then tau), normalization included. The spec (extra file
// kCheckpointSpecFile) records the clip, its frame count and the ranges, so that Rollout and
// QueryFamily take a by name; kCheckpointFamilyElitesFile carries the elite set (a in units, F);
// and, once the run has fitted it, parameterization(a [n, P] normalized, phase [n] in [0, 1])
// -> [n, D] is the parameterization network P(a). Written atomically.
#ifndef MODSKILL_LEARNER_FAMILY_FAMILY_EXPORT_H_
#define MODSKILL_LEARNER_FAMILY_FAMILY_EXPORT_H_

#include <string>

#include "absl/status/status.h"
#include "common/policy/family_parameters.h"
#include "common/policy/policy_spec.h"
#include "learner/family/elite_set.h"
#include "learner/family/family_policy.h"
#include "learner/family/parameterization_net.h"

namespace modskill::learner::family {

// The generated TorchScript source (for reading and tests); net null: forward only.
std::string FamilyScriptSource(const FamilyActorCriticImpl& model, const ParameterizationNetImpl* net);

// net null: the run has not fitted P(a) yet, so the archive has no parameterization method.
// INVALID_ARGUMENT when spec is not a family's or its sizes differ from the networks'.
absl::Status ExportFamilyPolicy(FamilyActorCriticImpl& model, const ParameterizationNetImpl* net,
                                const EliteSet& elites, const ParamSpace& space, const modskill::PolicySpec& spec,
                                const std::string& path);

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_FAMILY_EXPORT_H_
