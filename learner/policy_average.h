// Weight averaging of exported policies (stochastic weight averaging, Izmailov et al. 2018):
// the mean of every floating-point tensor of several policy.pt files written by one run, e.g. its
// last milestone exports. PPO's weights wander from update to update; a tracker evaluated from
// one export inherits that wander, the mean of neighbouring exports much less of it.
#ifndef MODSKILL_LEARNER_POLICY_AVERAGE_H_
#define MODSKILL_LEARNER_POLICY_AVERAGE_H_

#include <string>
#include <vector>

#include "absl/status/status.h"

namespace modskill::learner {

// Writes to `out` (atomically) the first of `inputs` with each of its floating-point tensors
// replaced by that tensor's mean over `inputs` (the observation statistics included), and its
// spec. INVALID_ARGUMENT naming the file when fewer than two inputs are given, an input is not
// an exported policy, or its spec, tensor names or shapes differ from the first input's.
absl::Status AveragePolicies(const std::vector<std::string>& inputs, const std::string& out);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_POLICY_AVERAGE_H_
