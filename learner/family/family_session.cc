#include "learner/family/family_session.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {

v1::SessionConfig FamilySessionConfig(const FamilySessionSettings& settings) {
  v1::SessionConfig session;
  session.set_num_envs(settings.num_envs);
  session.set_seed(settings.seed);
  session.add_motions(settings.clip);
  session.set_action_mode(v1::RESIDUAL);
  session.set_residual_scale(static_cast<float>(settings.residual_scale));
  session.set_termination_distance(static_cast<float>(settings.termination_distance));
  session.set_amp_obs(v1::OMIT);
  for (const ParamRange& range : settings.ranges) {
    v1::FamilyParameterRange* wire = session.mutable_family()->add_params();
    wire->set_name(range.name);
    wire->set_lo(range.lo);
    wire->set_hi(range.hi);
  }
  return session;
}

absl::StatusOr<v1::EnvSpec> DescribeFamilySession(SimulationClient& client, const PolicySpec& family) {
  if (!family.is_family()) {
    return absl::InvalidArgumentError("not a motor-skill family's policy (its spec has no family ranges)");
  }
  FamilySessionSettings settings;
  settings.clip = family.family_clip;
  settings.ranges = family.family;
  settings.residual_scale = family.action.residual_scale;
  auto stream = client.OpenSession(FamilySessionConfig(settings));
  if (!stream.ok()) {
    return absl::Status(stream.status().code(), absl::StrCat("opening the family session of '", family.family_clip,
                                                             "': ", stream.status().message()));
  }
  v1::EnvSpec spec = (*stream)->spec();
  // The spec is all that was asked for; a failed close costs the server a session it reaps.
  (*stream)->Close().IgnoreError();
  return spec;
}

}  // namespace modskill::learner::family
