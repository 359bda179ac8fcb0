#include "learner/policy_import.h"

#include <sstream>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "learner/skill_attention.h"

namespace modskill::learner {

absl::StatusOr<ExportedPolicy> ReadExportedPolicy(const std::string& path) {
  auto bytes = ReadFileToString(path, kMaxPolicyFileBytes);
  if (!bytes.ok()) return bytes.status();
  ExportedPolicy policy;
  policy.path = path;
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}};
  try {
    std::istringstream stream(*bytes, std::ios::binary);
    torch::jit::Module module = torch::jit::load(stream, torch::kCPU, extra);
    for (const auto& parameter : module.named_parameters(/*recurse=*/false)) {
      policy.tensors[parameter.name] = parameter.value.detach().clone();
    }
    for (const auto& buffer : module.named_buffers(/*recurse=*/false)) {
      policy.tensors[buffer.name] = buffer.value.detach().clone();
    }
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat(path, ": not a policy file (not a TorchScript archive: ",
                                                   message.substr(0, message.find('\n')), ")"));
  }
  if (extra[kCheckpointSpecFile].empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a policy file (no ", kCheckpointSpecFile, " inside the archive)"));
  }
  auto spec = PolicySpec::FromJson(extra[kCheckpointSpecFile]);
  if (!spec.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", spec.status().message()));
  if (spec->is_family()) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": a motor-skill family's policy (the family of '", spec->family_clip,
        "', modskill-learner --family), not a ModSkill tracker or task policy; run it with modskill-client rollout "
        "--param NAME=VALUE"));
  }
  policy.spec = *std::move(spec);
  return policy;
}

absl::StatusOr<std::vector<LinearWeights>> ExportedPolicy::Mlp(absl::string_view prefix) const {
  std::vector<LinearWeights> layers;
  for (int i = 0;; ++i) {
    const std::string weight = absl::StrCat(prefix, "_fc", i, "_weight"), bias = absl::StrCat(prefix, "_fc", i, "_bias");
    if (!Has(weight)) break;
    if (!Has(bias)) return absl::InvalidArgumentError(absl::StrCat(path, ": ", weight, " without ", bias));
    LinearWeights layer{tensors.at(weight), tensors.at(bias)};
    const bool chains = layers.empty() || layer.weight.dim() != 2 || layer.weight.size(1) == layers.back().weight.size(0);
    if (layer.weight.dim() != 2 || layer.bias.dim() != 1 || layer.bias.size(0) != layer.weight.size(0) || !chains) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": ", weight, " ", c10::str(layer.weight.sizes()), " and ",
                                                     bias, " ", c10::str(layer.bias.sizes()),
                                                     " are not a layer of the MLP ", prefix));
    }
    layers.push_back(layer);
  }
  return layers;
}

std::vector<int64_t> HiddenSizes(const std::vector<LinearWeights>& layers) {
  std::vector<int64_t> hidden;
  for (size_t i = 0; i + 1 < layers.size(); ++i) hidden.push_back(layers[i].weight.size(0));
  return hidden;
}

absl::Status CopyIntoMlp(const std::vector<LinearWeights>& layers, MlpImpl& mlp, absl::string_view what) {
  if (layers.size() != mlp.layers().size()) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": ", layers.size(), " layers, the network has ", mlp.layers().size()));
  }
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < layers.size(); ++i) {
    const torch::nn::Linear& layer = mlp.layers()[i];
    if (!layers[i].weight.sizes().equals(layer->weight.sizes()) || !layers[i].bias.sizes().equals(layer->bias.sizes())) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": layer ", i, " has weight ",
                                                     c10::str(layers[i].weight.sizes()), ", the network's is ",
                                                     c10::str(layer->weight.sizes())));
    }
    layer->weight.copy_(layers[i].weight);
    layer->bias.copy_(layers[i].bias);
  }
  return absl::OkStatus();
}

absl::Status CopyAttentionFrom(const ExportedPolicy& exported, SkillAttentionImpl& attention) {
  std::vector<std::pair<std::string, Mlp>> maps;  // Mlp handles (copies) can be written through
  for (size_t p = 0; p < attention.values().size(); ++p) {
    maps.emplace_back(absl::StrCat("part", p, "_value"), attention.values()[p]);
    if (!attention.uses_attention()) continue;
    maps.emplace_back(absl::StrCat("part", p, "_key"), attention.keys()[p]);
    maps.emplace_back(absl::StrCat("part", p, "_query"), attention.queries()[p]);
  }
  for (auto& [prefix, mlp] : maps) {
    auto layers = exported.Mlp(prefix);
    if (!layers.ok()) return layers.status();
    if (layers->empty()) return absl::InvalidArgumentError(absl::StrCat(exported.path, ": no ", prefix, " weights"));
    if (absl::Status status = CopyIntoMlp(*layers, *mlp, absl::StrCat(exported.path, ": ", prefix)); !status.ok()) {
      return status;
    }
  }
  return absl::OkStatus();
}

namespace {

// The sizes of the exported networks as a ModelConfig.
absl::StatusOr<ModelConfig> ConfigOfExport(const ExportedPolicy& exported, const NetworkLayout& layout) {
  auto invalid = [&](const std::string& why) { return absl::InvalidArgumentError(absl::StrCat(exported.path, ": ", why)); };
  auto value = exported.Mlp("part0_value");
  if (!value.ok()) return value.status();
  if (value->empty()) return invalid("no part0_value weights: not an exported ModSkill tracker");
  ModelConfig config;
  config.preset = "rebuilt";
  config.attention_hidden = HiddenSizes(*value);
  config.embed_dim = value->back().weight.size(0);
  config.attention = exported.Has("part0_key_fc0_weight");
  config.whole_body = exported.Has("whole_body_controller_fc0_weight");
  auto controller = exported.Mlp(config.whole_body ? "whole_body_controller" : "part0_controller");
  if (!controller.ok()) return controller.status();
  if (controller->empty()) return invalid("no controller weights");
  config.controller_hidden = HiddenSizes(*controller);
  auto input = ParseControllerInput(exported.spec.controller_input);
  if (!input.ok()) return invalid(std::string(input.status().message()));
  config.controller_input = *input;
  // Files from before the spec recorded controller_input: a proprioceptive controller reads z and
  // its bodies' self features only, which its first layer's width tells.
  if (!config.whole_body && !layout.parts.empty() &&
      controller->front().weight.size(1) == config.embed_dim + layout.parts[0].self_obs_size() &&
      layout.parts[0].self_obs_size() != layout.parts[0].obs_size) {
    config.controller_input = ModelConfig::ControllerInput::kProprioception;
  }
  if (!exported.Has("log_std") || exported.tensors.at("log_std").numel() < 1) return invalid("no log_std");
  config.log_std = exported.tensors.at("log_std").flatten()[0].item<double>();
  return config;
}

}  // namespace

absl::StatusOr<RebuiltPolicy> RebuildTracker(const ExportedPolicy& exported, const NetworkLayout& layout) {
  auto invalid = [&](const std::string& why) { return absl::InvalidArgumentError(absl::StrCat(exported.path, ": ", why)); };
  if (exported.spec.task != kTrackingTask) return invalid(absl::StrCat("a policy for task ", exported.spec.task));
  if (exported.Has("weight") && !exported.Has("obs_mean")) return invalid("an affine policy, not a ModSkill policy");
  if (layout.obs_size != exported.spec.obs_size || layout.has_goal()) {
    return invalid(absl::StrCat("trained on ", exported.spec.obs_size, " observation features, the layout has ",
                                layout.obs_size));
  }
  auto config = ConfigOfExport(exported, layout);
  if (!config.ok()) return config.status();
  RebuiltPolicy rebuilt;
  try {
    rebuilt.policy = ModSkillPolicy(layout, *config);
  } catch (const std::exception& e) {
    std::string message = e.what();
    return invalid(message.substr(0, message.find('\n')));
  }
  // Mlp handles (copies) can be written through.
  auto copy = [&](const std::string& prefix, Mlp mlp) -> absl::Status {
    auto layers = exported.Mlp(prefix);
    if (!layers.ok()) return layers.status();
    return CopyIntoMlp(*layers, *mlp, absl::StrCat(exported.path, ": ", prefix));
  };
  SkillAttention attention = rebuilt.policy->attention();
  if (absl::Status s = CopyAttentionFrom(exported, *attention); !s.ok()) return s;
  for (size_t p = 0; p < layout.parts.size() && !config->whole_body; ++p) {
    if (absl::Status s = copy(absl::StrCat("part", p, "_controller"), rebuilt.policy->controllers()[p]->mlp()); !s.ok()) {
      return s;
    }
  }
  if (config->whole_body) {
    if (absl::Status s = copy("whole_body_controller", rebuilt.policy->controllers()[0]->mlp()); !s.ok()) return s;
  }
  rebuilt.obs_norm = RunningMeanStd(layout.obs_size);
  torch::NoGradGuard no_grad;
  for (const char* name : {"obs_mean", "obs_var"}) {
    if (!exported.Has(name) || exported.tensors.at(name).numel() != layout.obs_size) return invalid(absl::StrCat("no ", name));
  }
  rebuilt.obs_norm->mean().copy_(exported.tensors.at("obs_mean"));
  rebuilt.obs_norm->var().copy_(exported.tensors.at("obs_var"));
  return rebuilt;
}

}  // namespace modskill::learner
