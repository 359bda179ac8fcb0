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

// Part p's controller and, with its attention, its value, key and query maps.
std::vector<const torch::nn::Module*> ModulesOfPart(const ModSkillPolicyImpl& policy, int p, bool with_attention) {
  std::vector<const torch::nn::Module*> modules = {policy.controllers()[p].get()};
  const SkillAttentionImpl& attention = *policy.attention();
  if (!with_attention) return modules;
  modules.push_back(attention.values()[p].get());
  if (attention.uses_attention()) {
    modules.push_back(attention.keys()[p].get());
    modules.push_back(attention.queries()[p].get());
  }
  return modules;
}

// `to` takes `from`'s weights: both are the same module of two policies built from one config.
void CopyWeights(const torch::nn::Module& from, const torch::nn::Module& to) {
  torch::NoGradGuard no_grad;
  const std::vector<torch::Tensor> sources = from.parameters(), targets = to.parameters();
  for (size_t i = 0; i < targets.size(); ++i) targets[i].copy_(sources[i]);
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
                                                          const ActionMapping& action, bool train_attention,
                                                          bool fresh_parts) {
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
  if (spec.obs_size != layout.obs_size) {
    return misfit(absl::StrCat("observes ", spec.reference_frames, " reference frame", spec.reference_frames > 1 ? "s" : "",
                               " (obs ", spec.obs_size, "); this run's sessions show obs ", layout.obs_size,
                               " (give --reference_frames ", spec.reference_frames, ")"));
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
  for (int p : tracker.trained_parts) {
    for (const torch::nn::Module* module : ModulesOfPart(policy, p, train_attention)) SetTrainable(*module, true);
  }
  if (fresh_parts) {
    // A policy as the trainer would start one: the fresh parts take its initial weights.
    const ModSkillPolicy fresh(layout, policy.config());
    for (int p : tracker.trained_parts) {
      const std::vector<const torch::nn::Module*> from = ModulesOfPart(*fresh, p, train_attention),
                                                  to = ModulesOfPart(policy, p, train_attention);
      for (size_t m = 0; m < to.size(); ++m) CopyWeights(*from[m], *to[m]);
    }
  }
  tracker.obs_norm->FreezeDims(torch::ones({layout.obs_size}, torch::kBool));
  return tracker;
}

}  // namespace modskill::learner
