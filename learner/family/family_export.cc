#include "learner/family/family_export.h"

#include <cmath>
#include <sstream>
#include <vector>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/family_elites.h"
#include "learner/torchscript_source.h"

namespace modskill::learner::family {
namespace {

absl::Status CheckSizes(const FamilyActorCriticImpl& model, const ParameterizationNetImpl* net,
                        const ParamSpace& space, const modskill::PolicySpec& spec) {
  const auto bad = [](const std::string& why) { return absl::InvalidArgumentError("ExportFamilyPolicy: " + why); };
  if (!spec.is_family() || static_cast<int>(spec.family.size()) != space.dims() || spec.family_frames < 2) {
    return bad("the spec is not this family's (clip, frames and ranges)");
  }
  if (spec.obs_size != model.config().obs_size || spec.action_size != model.config().action_size) {
    return bad(absl::StrCat("spec has obs_size ", spec.obs_size, ", action_size ", spec.action_size, "; the policy has ",
                            model.config().obs_size, ", ", model.config().action_size));
  }
  if (net != nullptr && (net->config().param_dims != space.dims() || net->config().outputs != spec.action_size)) {
    return bad("the parameterization network's sizes differ from the family's");
  }
  return absl::OkStatus();
}

// The elites in the parameters' units.
std::vector<FamilyEliteRecord> EliteRecords(const EliteSet& elites, const ParamSpace& space) {
  std::vector<FamilyEliteRecord> records;
  for (int64_t id : elites.Ids()) {
    const Elite& elite = elites.elite(id);
    absl::StatusOr<std::vector<double>> a = space.Denormalize(elite.params);
    if (a.ok()) records.push_back({*std::move(a), elite.fitness});
  }
  return records;
}

}  // namespace

std::string FamilyScriptSource(const FamilyActorCriticImpl& model, const ParameterizationNetImpl* net) {
  std::string src = "def forward(self, obs):\n";
  EmitNormalize("obs", "obs", &src);
  EmitLinearStack(model.policy_mlp(), "policy", "x", "a", &src);
  absl::StrAppend(&src, "    return a\n");
  if (net == nullptr) return src;
  // ParameterizationNetImpl::forward: the phase enters as (phase, sin 2 pi phase, cos 2 pi phase).
  absl::StrAppend(&src, "def parameterization(self, params, phase):\n", "    angle = ", ScriptFloat(2 * M_PI),
                  " * phase\n",
                  "    x = torch.cat([params, torch.unsqueeze(phase, 1), torch.unsqueeze(torch.sin(angle), 1), "
                  "torch.unsqueeze(torch.cos(angle), 1)], 1)\n");
  EmitLinearStack(net->mlp(), "parameterization", "x", "out", &src);
  absl::StrAppend(&src, "    return out\n");
  return src;
}

absl::Status ExportFamilyPolicy(FamilyActorCriticImpl& model, const ParameterizationNetImpl* net,
                                const EliteSet& elites, const ParamSpace& space, const modskill::PolicySpec& spec,
                                const std::string& path) {
  if (absl::Status status = CheckSizes(model, net, space, spec); !status.ok()) return status;
  try {
    torch::NoGradGuard no_grad;
    torch::jit::Module module("ModSkillFamilyPolicy");
    module.register_buffer("obs_mean", model.obs_norm()->mean().detach().clone());
    module.register_buffer("obs_var", model.obs_norm()->var().detach().clone());
    module.register_buffer("log_std", model.log_std().detach().clone());
    RegisterLinearStack(model.policy_mlp(), "policy", &module);
    if (net != nullptr) RegisterLinearStack(net->mlp(), "parameterization", &module);
    module.define(FamilyScriptSource(model, net));
    std::ostringstream out(std::ios::binary);
    module.save(out, {{kCheckpointSpecFile, spec.ToJson()},
                      {kCheckpointFamilyElitesFile, FamilyElitesToJson(EliteRecords(elites, space))}});
    return WriteFileAtomically(path, out.str());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("ExportFamilyPolicy: ", message.substr(0, message.find('\n'))));
  }
}

}  // namespace modskill::learner::family
