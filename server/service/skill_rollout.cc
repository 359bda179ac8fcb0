#include "server/service/skill_rollout.h"

#include <algorithm>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/shown_value.h"

namespace modskill {

bool WantsSkills(const v1::RolloutRequest& request) { return request.record_skills() || request.has_composition(); }

absl::Status CheckSkillRequest(const v1::RolloutRequest& request, const PolicyCheckpoint& checkpoint,
                               TaskKind task) {
  if (!WantsSkills(request)) return absl::OkStatus();
  const char* field = request.has_composition() ? "composition" : "record_skills";
  if (!checkpoint.skills_error().ok()) {
    return absl::FailedPreconditionError(absl::StrCat(field, ": ", checkpoint.skills_error().message()));
  }
  if (!checkpoint.has_skills()) {
    return absl::FailedPreconditionError(absl::StrCat(
        field, ": the checkpoint defines no skills() and act_with_z() (an affine policy, or a ModSkill policy "
               "exported before skill composition; re-export it with modskill-policy-upgrade)"));
  }
  if (!request.has_composition()) return absl::OkStatus();
  if (task != TaskKind::kTracking) {
    return absl::FailedPreconditionError(absl::StrCat("composition: the checkpoint is a policy for task ",
                                                      TaskInfoOf(task).name, "; composition needs a tracker"));
  }
  if (!checkpoint.has_part_controllers()) {
    return absl::FailedPreconditionError(
        "composition: the checkpoint has one whole-body controller (--whole_body), which reads every part's z; "
        "composition needs per-part controllers");
  }
  if (request.clips_size() > 0) {
    return absl::InvalidArgumentError("clips: leave empty with a composition (composition.base_clip names the clip)");
  }
  return absl::OkStatus();
}

absl::StatusOr<SkillComposition> ToComposition(const v1::SkillComposition& wire, const PartLayout& layout,
                                               const MotionLibrary& motions) {
  SkillComposition composition;
  composition.base_clip = motions.Find(wire.base_clip());
  if (composition.base_clip < 0) {
    return absl::NotFoundError(absl::StrCat("composition.base_clip: unknown clip '", ShownValue(wire.base_clip()), "'"));
  }
  composition.source_clip = motions.Find(wire.source_clip());
  if (composition.source_clip < 0) {
    return absl::NotFoundError(
        absl::StrCat("composition.source_clip: unknown clip '", ShownValue(wire.source_clip()), "'"));
  }
  std::vector<std::string> names;
  for (const BodyPart& part : layout.parts) names.push_back(part.name);
  if (wire.parts_size() == 0) return absl::InvalidArgumentError("composition.parts: name at least one part");
  for (int i = 0; i < wire.parts_size(); ++i) {
    const auto found = std::find(names.begin(), names.end(), wire.parts(i));
    if (found == names.end()) {
      return absl::InvalidArgumentError(absl::StrCat("composition.parts[", i, "]: unknown part '",
                                                     ShownValue(wire.parts(i)), "'; layout ", layout.name, " has ",
                                                     absl::StrJoin(names, ", ")));
    }
    composition.parts.push_back(static_cast<int>(found - names.begin()));
  }
  switch (wire.mode()) {
    case v1::COMPOSITION_MODE_UNSPECIFIED:
    case v1::SWAP:
      composition.mode = CompositionMode::kSwap;
      break;
    case v1::INTERPOLATE:
      composition.mode = CompositionMode::kInterpolate;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("composition.mode: unknown value ", static_cast<int>(wire.mode())));
  }
  return composition;
}

SkillPolicy SkillPolicyOf(PolicyCheckpoint& checkpoint, std::function<absl::Status()> check) {
  SkillPolicy policy;
  policy.num_parts = checkpoint.skill_parts();
  policy.embed_dim = checkpoint.embed_dim();
  policy.skills = [&checkpoint, check](const float* obs, int n, float* z) {
    if (absl::Status status = check(); !status.ok()) return status;
    return checkpoint.Skills(obs, n, z);
  };
  policy.act_with_z = [&checkpoint](const float* obs, const float* z, int n, float* actions) {
    return checkpoint.ActWithZ(obs, z, n, actions);
  };
  return policy;
}

void ToProto(const ComposedRolloutResult& result, const SkillComposition& composition, const PartLayout& layout,
             const MotionLibrary& motions, v1::CompositionReport* out) {
  out->set_source_clip(motions.clip(composition.source_clip).name);
  for (int part : composition.parts) out->add_parts(layout.parts[part].name);
  out->set_mode(composition.mode == CompositionMode::kInterpolate ? v1::INTERPOLATE : v1::SWAP);
  out->set_source_steps(result.source_steps);
  out->set_source_terminated(result.source_terminated);
  out->set_held_steps(result.held_steps);
}

}  // namespace modskill
