// Reading an exported policy.pt (policy_export.h) back into tensors: what a task policy needs
// from a tracker (its part controllers and observation statistics, skill_library.h) and what the
// task evaluation rebuilds a task policy from (task_evaluation.h).
#ifndef MODSKILL_LEARNER_POLICY_IMPORT_H_
#define MODSKILL_LEARNER_POLICY_IMPORT_H_

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <torch/torch.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/policy_spec.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/part_controller.h"
#include "learner/skill_attention.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

// One Linear layer as exported: weight [out, in], bias [out].
struct LinearWeights {
  torch::Tensor weight, bias;
};

struct ExportedPolicy {
  std::string path;
  PolicySpec spec;
  std::map<std::string, torch::Tensor> tensors;  // every parameter and buffer, by its flat name

  // The layers <prefix>_fc0, _fc1, ... in order (empty when there is no <prefix>_fc0).
  // INVALID_ARGUMENT naming the file and layer when a weight or bias is missing or its shape
  // does not chain.
  absl::StatusOr<std::vector<LinearWeights>> Mlp(absl::string_view prefix) const;
  bool Has(const std::string& name) const { return tensors.count(name) > 0; }
};

// INVALID_ARGUMENT naming `path` unless it is a TorchScript archive with a valid policy spec.
absl::StatusOr<ExportedPolicy> ReadExportedPolicy(const std::string& path);

// The hidden sizes of `layers` (every output but the last).
std::vector<int64_t> HiddenSizes(const std::vector<LinearWeights>& layers);

// Copies `layers` into `mlp` (same shapes, else INVALID_ARGUMENT naming `what`), without gradient.
absl::Status CopyIntoMlp(const std::vector<LinearWeights>& layers, MlpImpl& mlp, absl::string_view what);

// A tracker's exported networks rebuilt as modules, for re-exporting an older policy.pt with
// today's script (skills() and act_with_z(), policy_export.h): the ModSkillPolicy (sizes,
// attention or not, per-part or whole-body controllers and their input read from the tensors and
// the spec) and its observation normalizer.
// Copies the exported skill attention (part<p>_value, and part<p>_key / part<p>_query where
// `attention` uses attention) into `attention`, without gradient; INVALID_ARGUMENT naming the file
// and map when one is missing or does not fit.
absl::Status CopyAttentionFrom(const ExportedPolicy& exported, SkillAttentionImpl& attention);

struct RebuiltPolicy {
  ModSkillPolicy policy{nullptr};
  RunningMeanStd obs_norm{nullptr};
};

// `layout` is the server's for the policy's part_layout (LayoutFromWireSpec). INVALID_ARGUMENT
// naming the file for a task policy, an affine policy or tensors that do not fit `layout`.
absl::StatusOr<RebuiltPolicy> RebuildTracker(const ExportedPolicy& exported, const NetworkLayout& layout);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_POLICY_IMPORT_H_
