// Exports a trained ModSkill policy as the TorchScript checkpoint the server runs
// (common/policy/policy_checkpoint.h): forward(obs) maps RAW observations [N, obs_size] to the
// deterministic action means [N, action_size], normalization included. Two more methods split it
// for skill composition: skills(obs) -> z [N, P, E] (unit norm along E) and act_with_z(obs, z)
// -> actions (the controllers only); forward(obs) == act_with_z(obs, skills(obs)).
#ifndef MODSKILL_LEARNER_POLICY_EXPORT_H_
#define MODSKILL_LEARNER_POLICY_EXPORT_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/policy/policy_checkpoint.h"
#include "learner/amp_discriminator.h"
#include "learner/modskill_policy.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

// The C++ frontend's modules cannot be scripted, so the exporter copies every tensor the
// forward pass uses into a torch::jit::Module under a flat name (obs_mean, obs_var, log_std,
// part<p>_{key,query,value,controller}_fc<i>_{weight,bias} or whole_body_controller_fc<i>_...;
// a task policy has task_head_fc<i>_... instead of the attention's maps, or beside them with a
// skill prior) and defines a forward generated here, unrolled per part and per layer, with the
// same operations as RunningMeanStd::Normalize and ModSkillPolicy::forward (a task policy:
// normalize -> task head (+ the tracker's z_prior) -> z per part on the unit sphere -> the frozen
// controllers). The archive carries spec.ToJson() as
// the extra file kCheckpointSpecFile and is written atomically. INVALID_ARGUMENT when spec's
// sizes or task, or obs_norm's size, differ from the policy's layout.
absl::Status ExportPolicy(ModSkillPolicy& policy, RunningMeanStd& obs_norm, const modskill::PolicySpec& spec,
                          const std::string& path);

// The generated TorchScript source of ExportPolicy (for reading and tests).
std::string PolicyScriptSource(const ModSkillPolicyImpl& policy);

// The AMP discriminator as a plausibility scorer for the server's generated clips
// (ReportFailuresRequest.discriminator): a TorchScript archive whose forward maps RAW AMP
// observations [N, >= amp_norm size] (the server's whole history, newest frame first; the
// discriminator reads the first amp_norm.size() floats) to the AMP style reward
// max(0, 1 - 0.25 (D - 1)^2) in [0, 1]
// (1: indistinguishable from the reference motion), normalization included, as the trainer
// computes it. Returned as bytes, for sending.
absl::StatusOr<std::string> ExportDiscriminatorScorer(AmpDiscriminatorImpl& discriminator,
                                                      const RunningMeanStdImpl& amp_norm);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_POLICY_EXPORT_H_
