// Skill composition and interpolation (ModSkill's skill reuse, docs/DESIGN.md section 3): a
// policy split into skills(obs) -> z per body part and act_with_z(obs, z) -> actions records its
// z on clips, and replays a base clip with some parts' z taken from a source clip, swapped step
// for step or interpolated over time. Torch- and gRPC-free: the policy is two functions.
#ifndef MODSKILL_SERVER_CORE_ENV_SKILL_COMPOSITION_H_
#define MODSKILL_SERVER_CORE_ENV_SKILL_COMPOSITION_H_

#include <functional>
#include <memory>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/core/env/rollout.h"

namespace modskill {

// A policy in two halves; act_with_z(obs, skills(obs)) is its action.
struct SkillPolicy {
  int num_parts = 0;
  int embed_dim = 0;
  // obs: [n, obs_size] -> z: [n, num_parts, embed_dim], unit norm per part.
  std::function<absl::Status(const float* obs, int n, float* z)> skills;
  // obs: [n, obs_size], z: [n, num_parts, embed_dim] -> actions: [n, action_size].
  std::function<absl::Status(const float* obs, const float* z, int n, float* actions)> act_with_z;
};

enum class CompositionMode {
  kSwap,         // the chosen parts' z is the source's of the same step
  kInterpolate,  // normalize((1 - alpha) z_base + alpha z_source), alpha 0 -> 1 over the base rollout
};

struct SkillComposition {
  int base_clip = -1;    // index into the motions: the clip tracked
  int source_clip = -1;  // index into the motions: the clip whose z the chosen parts take
  std::vector<int> parts;  // part indices, distinct, at least one
  CompositionMode mode = CompositionMode::kSwap;
};

struct ComposedRolloutResult {
  ClipRolloutMetrics metrics;  // of the base clip
  int source_steps = 0;        // steps of the source episode whose z was recorded
  bool source_terminated = false;
  int held_steps = 0;  // base steps that used the source's last z (its episode had ended)
};

// Runs `clip_ids` as RunRollout does, acting with act_with_z(obs, skills(obs)), and shows each
// frame's z (RolloutFrameView.skill_z, num_parts * embed_dim floats).
absl::StatusOr<std::vector<ClipRolloutMetrics>> RunSkillRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                                const PartLayout& layout,
                                                                std::shared_ptr<const MotionLibrary> motions,
                                                                const std::vector<int>& clip_ids,
                                                                const SkillPolicy& policy,
                                                                const RolloutOptions& options,
                                                                const RolloutFrameCallback& on_frame = nullptr);

// Records the source clip's z per step (a rollout as in tracking), then rolls out the base clip
// with the chosen parts' z composed; `on_frame` sees the base rollout only, with the composed z.
// Past the source episode's end its last z is held. INVALID_ARGUMENT naming the field for parts
// out of range or repeated, none, or a policy whose num_parts is not the layout's; NOT_FOUND for
// a clip index outside `motions`.
absl::StatusOr<ComposedRolloutResult> RunComposedRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                         const PartLayout& layout,
                                                         std::shared_ptr<const MotionLibrary> motions,
                                                         const SkillPolicy& policy,
                                                         const SkillComposition& composition,
                                                         const RolloutOptions& options,
                                                         const RolloutFrameCallback& on_frame = nullptr);

// alpha of base step `step` in a rollout that can last `possible_steps`: 0 at the first step,
// 1 at the last, linear between.
double InterpolationAlpha(int step, int possible_steps);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_SKILL_COMPOSITION_H_
