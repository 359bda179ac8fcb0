#include "learner/part_retraining.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "common/name_lookup.h"
#include "learner/policy_import.h"

namespace modskill::learner {
namespace {

void SetTrainable(const torch::nn::Module& module, bool trainable) {
  for (torch::Tensor parameter : module.parameters()) parameter.set_requires_grad(trainable);  // shares the storage
}

absl::StatusOr<std::vector<int>> PartIndices(const std::vector<std::string>& names, const std::string& layout_name,
                                              const NetworkLayout& layout) {
  std::vector<std::string> known;
  for (const PartSlices& part : layout.parts) known.push_back(part.name);
  return IndicesOfNames(names, known, "--train_parts", absl::StrCat("a part of the ", layout_name, " layout"));
}

}  // namespace

absl::StatusOr<RetrainedTracker> LoadTrackerForRetraining(const std::string& path, const std::vector<std::string>& train_parts,
                                                          const std::string& layout_name, const NetworkLayout& layout,
                                                          const ActionMapping& action, bool train_attention) {
  auto exported = ReadExportedPolicy(path);
  if (!exported.ok()) return absl::Status(exported.status().code(), absl::StrCat("--init_from: ", exported.status().message()));
  const PolicySpec& spec = exported->spec;
  const auto misfit = [&](const std::string& why) {
    return absl::FailedPreconditionError(absl::StrCat("--init_from: ", path, ": ", why));
  };
  if (spec.part_layout != layout_name) {
    return misfit(absl::StrCat("trained with layout ", spec.part_layout, ", this run uses ", layout_name));
  }
  if (spec.action.mode != action.mode ||
      (action.mode == ActionMode::kResidual && std::abs(spec.action.residual_scale - action.residual_scale) > 1e-9)) {
    return misfit(absl::StrCat("trained in ", ActionModeName(spec.action.mode), " mode (residual_scale ",
                               spec.action.residual_scale, "); this run uses ", ActionModeName(action.mode),
                               " (residual_scale ", action.residual_scale, ")"));
  }
  auto parts = PartIndices(train_parts, layout_name, layout);
  if (!parts.ok()) return parts.status();
  auto rebuilt = RebuildTracker(*exported, layout);
  if (!rebuilt.ok()) return absl::Status(rebuilt.status().code(), absl::StrCat("--init_from: ", rebuilt.status().message()));
  RetrainedTracker tracker{rebuilt->policy, rebuilt->obs_norm, *parts};
  if (train_parts.empty()) {
    for (size_t p = 0; p < layout.parts.size(); ++p) tracker.trained_parts.push_back(static_cast<int>(p));
    return tracker;
  }
  ModSkillPolicyImpl& policy = *tracker.policy;
  if (policy.config().whole_body) return misfit("a whole-body tracker has no part controllers to retrain apart");
  SetTrainable(policy, false);
  const SkillAttentionImpl& attention = *policy.attention();
  for (int p : tracker.trained_parts) {
    SetTrainable(*policy.controllers()[p], true);
    if (!train_attention) continue;
    SetTrainable(*attention.values()[p], true);
    if (attention.uses_attention()) {
      SetTrainable(*attention.keys()[p], true);
      SetTrainable(*attention.queries()[p], true);
    }
  }
  tracker.obs_norm->FreezeDims(torch::ones({layout.obs_size}, torch::kBool));
  return tracker;
}

}  // namespace modskill::learner
