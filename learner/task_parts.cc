#include "learner/task_parts.h"

#include "absl/strings/str_cat.h"
#include "common/name_lookup.h"

namespace modskill::learner {

absl::StatusOr<torch::Tensor> RestrictTaskHeadToParts(ModSkillPolicyImpl& policy, const std::vector<std::string>& parts,
                                                      const std::string& layout_name) {
  if (!policy.uses_skill_prior()) {
    return absl::FailedPreconditionError(absl::StrCat("--task_parts: task '", policy.layout().task,
                                                      "' has no skill prior for the other parts to play"));
  }
  std::vector<std::string> known;
  for (const PartSlices& part : policy.layout().parts) known.push_back(part.name);
  auto indices = IndicesOfNames(parts, known, "--task_parts", absl::StrCat("a part of the ", layout_name, " layout"));
  if (!indices.ok()) return indices.status();
  const int64_t embed = policy.config().embed_dim;
  torch::Tensor mask = torch::zeros({policy.sample_size()});
  for (int p : *indices) mask.slice(0, p * embed, (p + 1) * embed).fill_(1.f);
  torch::NoGradGuard no_grad;
  const auto& last = policy.task_head()->layers().back();
  last->weight.mul_(mask.unsqueeze(1));
  last->bias.mul_(mask);
  return mask;
}

}  // namespace modskill::learner
