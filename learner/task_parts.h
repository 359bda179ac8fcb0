// A task head over a subset of the parts (--task_parts): the head displaces only those parts' z,
// and every other part plays the skill prior's z. A reach moves one arm; exploring all five
// parts' z (160 dims in `small`) buries the arm's share of PPO's gradient under the noise of the
// legs and torso, which only risks a fall.
#ifndef MODSKILL_LEARNER_TASK_PARTS_H_
#define MODSKILL_LEARNER_TASK_PARTS_H_

#include <string>
#include <vector>

#include <torch/torch.h>

#include "absl/status/statusor.h"
#include "learner/modskill_policy.h"

namespace modskill::learner {

// Zeroes the rows of the task head's last layer that belong to parts outside `parts`, so that
// the head's mean displacement of their z is 0, and returns the sample space's mask ([P * E],
// 1 over `parts`' z, 0 elsewhere) for PpoSettings::sampled_dims and the exploration noise. With
// that mask the zeroed rows get no gradient, so they stay 0 through training, and the exported
// policy plays the prior there without knowing of the mask. INVALID_ARGUMENT naming --task_parts
// for a name that is not a part of the layout; FAILED_PRECONDITION when the policy has no skill
// prior to fall back on.
absl::StatusOr<torch::Tensor> RestrictTaskHeadToParts(ModSkillPolicyImpl& policy, const std::vector<std::string>& parts,
                                                      const std::string& layout_name);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TASK_PARTS_H_
