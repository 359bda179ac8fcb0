#include "learner/torchscript_source.h"

#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {
namespace {

// The Linear layers of a Linear/ReLU stack, in order.
std::vector<torch::nn::Linear> LinearLayers(const torch::nn::Sequential& mlp) {
  std::vector<torch::nn::Linear> layers;
  for (const auto& module : mlp->children()) {
    if (auto linear = std::dynamic_pointer_cast<torch::nn::LinearImpl>(module)) {
      layers.emplace_back(linear);
    } else if (!std::dynamic_pointer_cast<torch::nn::ReLUImpl>(module)) {
      throw std::invalid_argument("a network with a layer other than Linear and ReLU cannot be exported");
    }
  }
  return layers;
}

}  // namespace

std::string LayerName(absl::string_view prefix, size_t layer, absl::string_view tensor) {
  return absl::StrCat(prefix, "_fc", layer, "_", tensor);
}

void RegisterLinearLayers(const std::vector<torch::nn::Linear>& layers, absl::string_view prefix,
                          torch::jit::Module* module) {
  for (size_t i = 0; i < layers.size(); ++i) {
    module->register_parameter(LayerName(prefix, i, "weight"), layers[i]->weight.detach().clone(), /*is_buffer=*/false);
    module->register_parameter(LayerName(prefix, i, "bias"), layers[i]->bias.detach().clone(), /*is_buffer=*/false);
  }
}

void EmitLinearLayers(size_t num_layers, absl::string_view activation, absl::string_view prefix,
                      absl::string_view input, absl::string_view output, std::string* source) {
  std::string x(input);
  for (size_t i = 0; i < num_layers; ++i) {
    const bool last = i + 1 == num_layers;
    const std::string target = last ? std::string(output) : "h";
    absl::StrAppend(source, "    ", target, " = torch.addmm(self.", LayerName(prefix, i, "bias"), ", ", x, ", self.",
                    LayerName(prefix, i, "weight"), ".t())\n");
    if (!last) absl::StrAppend(source, "    h = torch.", activation, "(h)\n");
    x = "h";
  }
}

std::string ScriptFloat(double value) {
  std::string text;
  for (int precision = 1; precision <= 17; ++precision) {
    text = absl::StrFormat("%.*g", precision, value);
    if (std::strtod(text.c_str(), nullptr) == value) break;
  }
  if (text.find_first_of(".en") == std::string::npos) text += ".0";
  return text;
}

void EmitNormalize(absl::string_view input, absl::string_view stats, std::string* source) {
  absl::StrAppend(source, "    x = torch.clamp((", input, " - self.", stats, "_mean.to(", input, ".dtype)) / torch.sqrt(self.",
                  stats, "_var + ", ScriptFloat(RunningMeanStdImpl::kEpsilon), ").to(", input, ".dtype), ",
                  ScriptFloat(-RunningMeanStdImpl::kClip), ", ", ScriptFloat(RunningMeanStdImpl::kClip), ")\n");
}

void RegisterLinearStack(const torch::nn::Sequential& mlp, absl::string_view prefix, torch::jit::Module* module) {
  RegisterLinearLayers(LinearLayers(mlp), prefix, module);
}

void EmitLinearStack(const torch::nn::Sequential& mlp, absl::string_view prefix, absl::string_view input,
                     absl::string_view output, std::string* source) {
  EmitLinearLayers(LinearLayers(mlp).size(), "relu", prefix, input, output, source);
}

}  // namespace modskill::learner
