#include "learner/policy_import.h"

#include <sstream>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"

namespace modskill::learner {

absl::StatusOr<ExportedPolicy> ReadExportedPolicy(const std::string& path) {
  auto bytes = ReadFileToString(path, size_t{2} << 30);
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

}  // namespace modskill::learner
