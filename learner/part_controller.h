// The low-level controller of one body part (ModSkill): an MLP from [z_k, part k's observation]
// to the means of part k's actions. Also the MLP that every network of the learner is built from.
#ifndef MODSKILL_LEARNER_PART_CONTROLLER_H_
#define MODSKILL_LEARNER_PART_CONTROLLER_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

namespace modskill::learner {

enum class Activation { kElu, kRelu };

// Linear layers fc0 ... fcN (registered under those names): input -> hidden... -> output, the
// activation after every hidden layer, a linear output.
class MlpImpl : public torch::nn::Module {
 public:
  MlpImpl(int64_t input_size, const std::vector<int64_t>& hidden, int64_t output_size, Activation activation);

  // x: [B, input_size] -> [B, output_size]
  torch::Tensor forward(const torch::Tensor& x);

  const std::vector<torch::nn::Linear>& layers() const { return layers_; }
  torch::nn::Linear& output_layer() { return layers_.back(); }
  Activation activation() const { return activation_; }

 private:
  std::vector<torch::nn::Linear> layers_;
  Activation activation_;
};
TORCH_MODULE(Mlp);

// The controller of part k; its input is [z_k, obs slice of part k].
class PartControllerImpl : public torch::nn::Module {
 public:
  PartControllerImpl(int64_t input_size, int64_t action_size, const std::vector<int64_t>& hidden);

  // input: [B, input_size] -> action means: [B, action_size] (ELU MLP, linear output)
  torch::Tensor forward(const torch::Tensor& input);

  const Mlp& mlp() const { return mlp_; }
  int64_t input_size() const { return input_size_; }
  int64_t action_size() const { return action_size_; }

 private:
  int64_t input_size_, action_size_;
  Mlp mlp_;
};
TORCH_MODULE(PartController);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_PART_CONTROLLER_H_
