#include "learner/acting_networks.h"

namespace modskill::learner {

void CopyModuleState(const torch::nn::Module& from, torch::nn::Module& to) {
  torch::NoGradGuard no_grad;
  const auto source_parameters = from.named_parameters();
  for (auto& target : to.named_parameters()) target.value().copy_(source_parameters[target.key()]);
  const auto source_buffers = from.named_buffers();
  for (auto& target : to.named_buffers()) target.value().copy_(source_buffers[target.key()]);
}

}  // namespace modskill::learner
