// The skill side of a Rollout request (RolloutRequest.record_skills and .composition): checked
// against the checkpoint, translated to the core's SkillPolicy and SkillComposition
// (server/core/env/skill_composition.h), and the composition's report back to the wire.
#ifndef MODSKILL_SERVER_SERVICE_SKILL_ROLLOUT_H_
#define MODSKILL_SERVER_SERVICE_SKILL_ROLLOUT_H_

#include <functional>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/policy/policy_checkpoint.h"
#include "modskill/v1/modskill.pb.h"
#include "server/core/env/skill_composition.h"

namespace modskill {

// Whether the request needs the checkpoint's skills() and act_with_z().
bool WantsSkills(const v1::RolloutRequest& request);

// FAILED_PRECONDITION naming the field when the checkpoint cannot do what the request asks:
// no skills() (an older export or an affine policy), or, for a composition, a task policy or a
// whole-body controller. INVALID_ARGUMENT when a composition also names `clips`.
absl::Status CheckSkillRequest(const v1::RolloutRequest& request, const PolicyCheckpoint& checkpoint,
                               TaskKind task);

// The composition by index: NOT_FOUND naming composition.base_clip or .source_clip for an unknown
// clip, INVALID_ARGUMENT naming composition.parts[i] for a part not in `layout` (the message
// lists its parts) or named twice, and composition.mode for an unknown mode.
absl::StatusOr<SkillComposition> ToComposition(const v1::SkillComposition& wire, const PartLayout& layout,
                                               const MotionLibrary& motions);

// The checkpoint's two halves as a SkillPolicy; `check` runs before each call (a client that went
// away stops the rollout there).
SkillPolicy SkillPolicyOf(PolicyCheckpoint& checkpoint, std::function<absl::Status()> check);

void ToProto(const ComposedRolloutResult& result, const SkillComposition& composition, const PartLayout& layout,
             const MotionLibrary& motions, v1::CompositionReport* out);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SKILL_ROLLOUT_H_
