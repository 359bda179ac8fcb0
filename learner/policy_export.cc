#include "learner/policy_export.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "common/atomic_file.h"
#include "learner/torchscript_source.h"

namespace modskill::learner {
namespace {

std::string PartPrefix(size_t part, absl::string_view role) { return absl::StrCat("part", part, "_", role); }

// Emits `output = mlp(input)`, the same ops as MlpImpl::forward.
void EmitMlp(const MlpImpl& mlp, absl::string_view prefix, absl::string_view input, absl::string_view output,
             std::string* source) {
  EmitLinearLayers(mlp.layers().size(), mlp.activation() == Activation::kElu ? "elu" : "relu", prefix, input, output,
                   source);
}

void RegisterMlp(const MlpImpl& mlp, absl::string_view prefix, torch::jit::Module* module) {
  RegisterLinearLayers(mlp.layers(), prefix, module);
}

std::string Slice(const PartSlices& part) {
  return absl::StrCat("x[:, ", part.obs_start, ":", part.obs_start + part.obs_size, "]");
}

// ModSkillPolicy::ControllerState as TorchScript: the part's slice, or its bodies' self slices.
std::string ControllerState(const ModSkillPolicyImpl& policy, size_t p) {
  const PartSlices& part = policy.layout().parts[p];
  if (!policy.proprioceptive()) return Slice(part);
  std::vector<std::string> slices;
  for (const auto& [start, size] : part.self_obs) slices.push_back(absl::StrCat("x[:, ", start, ":", start + size, "]"));
  return absl::StrCat("torch.cat([", absl::StrJoin(slices, ", "), "], 1)");
}

// Emits z [B, P, E] (unit norm along E) from the skill attention's key, query and value maps.
void EmitSkillAttention(const ModSkillPolicyImpl& policy, std::string* src) {
  const NetworkLayout& layout = policy.layout();
  const SkillAttentionImpl& attention = *policy.attention();
  std::vector<std::string> keys, queries, values;
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    const PartSlices& part = layout.parts[p];
    absl::StrAppend(src, "    # part ", p, " '", part.name, "': obs [", part.obs_start, ", ",
                    part.obs_start + part.obs_size, "), actions [", part.action_start, ", ",
                    part.action_start + part.action_size, ")\n");
    absl::StrAppend(src, "    s", p, " = ", Slice(part), "\n");
    const std::string s = absl::StrCat("s", p);
    values.push_back(absl::StrCat("v", p));
    EmitMlp(*attention.values()[p], PartPrefix(p, "value"), s, values.back(), src);
    if (attention.uses_attention()) {
      keys.push_back(absl::StrCat("k", p));
      queries.push_back(absl::StrCat("q", p));
      EmitMlp(*attention.keys()[p], PartPrefix(p, "key"), s, keys.back(), src);
      EmitMlp(*attention.queries()[p], PartPrefix(p, "query"), s, queries.back(), src);
    }
  }
  absl::StrAppend(src, "    v = torch.stack([", absl::StrJoin(values, ", "), "], 1)\n");
  if (attention.uses_attention()) {
    absl::StrAppend(src, "    q = torch.stack([", absl::StrJoin(queries, ", "), "], 1)\n");
    absl::StrAppend(src, "    k = torch.stack([", absl::StrJoin(keys, ", "), "], 1)\n");
    absl::StrAppend(src, "    alpha = torch.softmax(torch.matmul(q, k.transpose(1, 2)) / ",
                    ScriptFloat(std::sqrt(static_cast<double>(attention.embed_dim()))), ", -1)\n");
    absl::StrAppend(src, "    z = torch.matmul(alpha, v)\n");
  } else {
    absl::StrAppend(src, "    z = v\n");
  }
}

// Emits z [B, P, E] from the task head (skill reuse): its raw output viewed per part.
void EmitTaskHead(const ModSkillPolicyImpl& policy, std::string* src) {
  const NetworkLayout& layout = policy.layout();
  absl::StrAppend(src, "    # task '", layout.task, "': goal obs [", layout.goal_start, ", ",
                  layout.goal_start + layout.goal_size, "); one z per part from the task head\n");
  std::string prior;
  if (policy.uses_skill_prior()) {
    // The tracker's attention on the anchored base motion gives z_prior; the head displaces it.
    EmitSkillAttention(policy, src);
    absl::StrAppend(src, "    z = z / torch.clamp_min(torch.sqrt(torch.sum(z * z, [-1], True)), ",
                    ScriptFloat(SkillAttentionImpl::kMinNorm), ")\n");
    prior = "z + ";
  }
  EmitMlp(*policy.task_head(), "task_head", "x", "h", src);
  absl::StrAppend(src, "    z = ", prior, "torch.reshape(h, [-1, ", layout.parts.size(), ", ", policy.config().embed_dim,
                  "])\n");
}

// Emits the actions from z: the part controllers (or the whole-body one), returned.
void EmitControllers(const ModSkillPolicyImpl& policy, std::string* src) {
  if (policy.config().whole_body) {
    absl::StrAppend(src, "    c = torch.cat([torch.flatten(z, 1), x], 1)\n");
    EmitMlp(*policy.controllers()[0]->mlp(), "whole_body_controller", "c", "a", src);
    absl::StrAppend(src, "    return a\n");
    return;
  }
  std::vector<std::string> actions;
  for (size_t p = 0; p < policy.layout().parts.size(); ++p) {
    absl::StrAppend(src, "    c", p, " = torch.cat([z[:, ", p, "], ", ControllerState(policy, p), "], 1)\n");
    actions.push_back(absl::StrCat("a", p));
    EmitMlp(*policy.controllers()[p]->mlp(), PartPrefix(p, "controller"), absl::StrCat("c", p), actions.back(), src);
  }
  absl::StrAppend(src, "    return torch.cat([", absl::StrJoin(actions, ", "), "], 1)\n");
}

// Registers every tensor PolicyScriptSource reads, under the names it reads them by.
void RegisterPolicyTensors(ModSkillPolicy& policy, RunningMeanStd& obs_norm, torch::jit::Module* module) {
  const NetworkLayout& layout = policy->layout();
  module->register_buffer("obs_mean", obs_norm->mean().detach().clone());
  module->register_buffer("obs_var", obs_norm->var().detach().clone());
  module->register_buffer("log_std", policy->log_std().detach().clone());
  if (policy->task_mode()) RegisterMlp(*policy->task_head(), "task_head", module);
  if (!policy->task_mode() || policy->uses_skill_prior()) {
    const SkillAttentionImpl& attention = *policy->attention();
    for (size_t p = 0; p < layout.parts.size(); ++p) {
      RegisterMlp(*attention.values()[p], PartPrefix(p, "value"), module);
      if (attention.uses_attention()) {
        RegisterMlp(*attention.keys()[p], PartPrefix(p, "key"), module);
        RegisterMlp(*attention.queries()[p], PartPrefix(p, "query"), module);
      }
    }
  }
  if (policy->config().whole_body) {
    RegisterMlp(*policy->controllers()[0]->mlp(), "whole_body_controller", module);
  } else {
    for (size_t p = 0; p < layout.parts.size(); ++p) {
      RegisterMlp(*policy->controllers()[p]->mlp(), PartPrefix(p, "controller"), module);
    }
  }
}

}  // namespace

std::string PolicyScriptSource(const ModSkillPolicyImpl& policy) {
  // skills(obs) -> z [N, P, E] on the unit sphere, and act_with_z(obs, z) -> actions: the two
  // halves of forward, so that the server can record, swap and interpolate z (skill composition).
  // forward stays one unrolled function: forward(obs) == act_with_z(obs, skills(obs)).
  std::string src;
  for (const char* method : {"forward", "skills"}) {
    absl::StrAppend(&src, "def ", method, "(self, obs):\n", "    # RunningMeanStd::Normalize\n");
    EmitNormalize("obs", "obs", &src);
    if (policy.task_mode()) {
      EmitTaskHead(policy, &src);
    } else {
      EmitSkillAttention(policy, &src);
    }
    absl::StrAppend(&src, "    z = z / torch.clamp_min(torch.sqrt(torch.sum(z * z, [-1], True)), ",
                    ScriptFloat(SkillAttentionImpl::kMinNorm), ")\n");
    if (std::string(method) == "forward") {
      EmitControllers(policy, &src);
    } else {
      absl::StrAppend(&src, "    return z\n");
    }
  }
  absl::StrAppend(&src, "def act_with_z(self, obs, z_in):\n");
  EmitNormalize("obs", "obs", &src);
  absl::StrAppend(&src, "    z = z_in.to(x.dtype)\n");
  EmitControllers(policy, &src);
  return src;
}

absl::Status ExportPolicy(ModSkillPolicy& policy, RunningMeanStd& obs_norm, const modskill::PolicySpec& spec,
                          const std::string& path) {
  const NetworkLayout& layout = policy->layout();
  if (spec.obs_size != layout.obs_size || spec.action_size != layout.action_size) {
    return absl::InvalidArgumentError(absl::StrCat("ExportPolicy: spec has obs_size ", spec.obs_size, ", action_size ",
                                                   spec.action_size, "; the policy has ", layout.obs_size, ", ",
                                                   layout.action_size));
  }
  if (spec.task != layout.task) {
    return absl::InvalidArgumentError(
        absl::StrCat("ExportPolicy: spec has task ", spec.task, "; the policy's is ", layout.task));
  }
  if (obs_norm->size() != layout.obs_size) {
    return absl::InvalidArgumentError(absl::StrCat("ExportPolicy: obs_norm has size ", obs_norm->size(),
                                                   ", the policy's obs_size is ", layout.obs_size));
  }
  try {
    torch::NoGradGuard no_grad;
    torch::jit::Module module("ModSkillPolicy");
    RegisterPolicyTensors(policy, obs_norm, &module);
    module.define(PolicyScriptSource(*policy));
    std::ostringstream out(std::ios::binary);
    module.save(out, {{kCheckpointSpecFile, spec.ToJson()}});
    return WriteFileAtomically(path, out.str());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("ExportPolicy: ", message.substr(0, message.find('\n'))));
  }
}

absl::StatusOr<std::string> ExportDiscriminatorScorer(AmpDiscriminatorImpl& discriminator,
                                                      const RunningMeanStdImpl& amp_norm) {
  const MlpImpl& mlp = *discriminator.mlp();
  if (amp_norm.size() != mlp.layers().front()->weight.size(1)) {
    return absl::InvalidArgumentError(absl::StrCat("ExportDiscriminatorScorer: amp_norm has size ", amp_norm.size(),
                                                   ", the discriminator takes ", mlp.layers().front()->weight.size(1)));
  }
  try {
    torch::NoGradGuard no_grad;
    torch::jit::Module module("AmpDiscriminatorScorer");
    module.register_buffer("amp_mean", amp_norm.mean().detach().clone());
    module.register_buffer("amp_var", amp_norm.var().detach().clone());
    RegisterMlp(mlp, "discriminator", &module);
    // The server scores its full AMP history; the discriminator reads the newest frames of it.
    std::string src = absl::StrCat("def forward(self, amp_obs):\n    amp_obs = amp_obs[:, 0:", amp_norm.size(), "]\n");
    EmitNormalize("amp_obs", "amp", &src);
    EmitMlp(mlp, "discriminator", "x", "logit", &src);
    absl::StrAppend(&src, "    logit = logit.reshape([-1])\n",
                    "    return torch.clamp(1.0 - 0.25 * (logit - 1.0) * (logit - 1.0), 0.0, 1.0)\n");
    module.define(src);
    std::ostringstream out(std::ios::binary);
    module.save(out);
    return out.str();
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("ExportDiscriminatorScorer: ", message.substr(0, message.find('\n'))));
  }
}

}  // namespace modskill::learner
