// The networks a collection acts with: the policy, the critic (behaviour values for GAE) and the
// observation normalizer. While the update runs, the next collection acts with a copy of them
// taken before the update (Sample Factory's policy lag of one), so the two never share weights.
#ifndef MODSKILL_LEARNER_ACTING_NETWORKS_H_
#define MODSKILL_LEARNER_ACTING_NETWORKS_H_

#include <torch/torch.h>

#include "learner/critic.h"
#include "learner/modskill_policy.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

struct ActingNetworks {
  ModSkillPolicy policy{nullptr};
  Critic critic{nullptr};
  RunningMeanStd obs_norm{nullptr};
  int64_t version = 0;  // policy updates the weights have seen
};

// Copies every parameter and buffer of `from` into `to` (same architecture), without gradients.
void CopyModuleState(const torch::nn::Module& from, torch::nn::Module& to);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_ACTING_NETWORKS_H_
