#include "learner/part_controller.h"

#include <string>

namespace modskill::learner {

MlpImpl::MlpImpl(int64_t input_size, const std::vector<int64_t>& hidden, int64_t output_size,
                 Activation activation)
    : activation_(activation) {
  int64_t in = input_size;
  for (size_t i = 0; i <= hidden.size(); ++i) {
    const int64_t out = i < hidden.size() ? hidden[i] : output_size;
    layers_.push_back(register_module("fc" + std::to_string(i), torch::nn::Linear(in, out)));
    in = out;
  }
}

torch::Tensor MlpImpl::forward(const torch::Tensor& x) {
  torch::Tensor h = x;
  for (size_t i = 0; i < layers_.size(); ++i) {
    h = layers_[i]->forward(h);
    if (i + 1 < layers_.size()) h = activation_ == Activation::kElu ? torch::elu(h) : torch::relu(h);
  }
  return h;
}

PartControllerImpl::PartControllerImpl(int64_t input_size, int64_t action_size, const std::vector<int64_t>& hidden)
    : input_size_(input_size),
      action_size_(action_size),
      mlp_(register_module("mlp", Mlp(input_size, hidden, action_size, Activation::kElu))) {
  // Action means start near 0 (PD targets near the joints' mid-range), as PPO policy heads
  // usually do: a default-initialized head commands random poses up to pi away and every first
  // episode ends within two steps.
  torch::NoGradGuard no_grad;
  mlp_->output_layer()->weight.mul_(0.01);
  mlp_->output_layer()->bias.zero_();
}

torch::Tensor PartControllerImpl::forward(const torch::Tensor& input) { return mlp_->forward(input); }

}  // namespace modskill::learner
