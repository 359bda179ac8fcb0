// Pieces of the TorchScript source the exporters generate (policy_export.h, family/family_export.h):
// the C++ frontend's modules cannot be scripted, so each exporter registers the tensors a forward
// pass reads under flat names and defines that pass as source text with the same operations.
#ifndef MODSKILL_LEARNER_TORCHSCRIPT_SOURCE_H_
#define MODSKILL_LEARNER_TORCHSCRIPT_SOURCE_H_

#include <string>
#include <vector>

#include <torch/script.h>
#include <torch/torch.h>

#include "absl/strings/string_view.h"

namespace modskill::learner {

// The shortest decimal that reads back as `value`, always a float literal for TorchScript.
std::string ScriptFloat(double value);

// Emits `x = RunningMeanStd::Normalize(input)` with the registered buffers `<stats>_mean` and
// `<stats>_var`.
void EmitNormalize(absl::string_view input, absl::string_view stats, std::string* source);

// `<prefix>_fc<i>_<tensor>`, the flat name a layer's weight or bias is registered under.
std::string LayerName(absl::string_view prefix, size_t layer, absl::string_view tensor);

// Registers each layer's weight and bias under LayerName (copies, without gradient).
void RegisterLinearLayers(const std::vector<torch::nn::Linear>& layers, absl::string_view prefix,
                          torch::jit::Module* module);
// Emits `output = layers(input)` line by line, `activation` ("relu", "elu") after every layer but
// the last (Linear on a 2-d input is addmm(bias, x, weight^T)).
void EmitLinearLayers(size_t num_layers, absl::string_view activation, absl::string_view prefix,
                      absl::string_view input, absl::string_view output, std::string* source);

// A torch::nn::Sequential of Linear layers with ReLU between them (the family's networks):
// registers `<prefix>_fc<i>_{weight,bias}` and emits `output = mlp(input)`, ReLU after every
// layer but the last. INVALID_ARGUMENT-worthy layouts (another module kind) throw.
void RegisterLinearStack(const torch::nn::Sequential& mlp, absl::string_view prefix, torch::jit::Module* module);
void EmitLinearStack(const torch::nn::Sequential& mlp, absl::string_view prefix, absl::string_view input,
                     absl::string_view output, std::string* source);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TORCHSCRIPT_SOURCE_H_
