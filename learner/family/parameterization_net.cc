#include "learner/family/parameterization_net.h"

#include <ATen/CPUGeneratorImpl.h>

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {
namespace {

constexpr int64_t kPhaseFeatures = 3;  // phase, sin 2 pi phase, cos 2 pi phase

absl::Status CheckData(const ParameterizationNetConfig& config, const ParameterizationData& data) {
  const auto bad = [](const std::string& what) { return absl::InvalidArgumentError("parameterization data: " + what); };
  if (!data.params.defined() || !data.phase.defined() || !data.targets.defined()) return bad("params, phase and targets are required");
  const int64_t m = data.params.dim() == 2 ? data.params.size(0) : -1;
  if (m < 1 || data.params.size(1) != config.param_dims) return bad(absl::StrCat("params must be [M >= 1, ", config.param_dims, "]"));
  if (data.phase.dim() != 1 || data.phase.size(0) != m) return bad(absl::StrCat("phase must be [", m, "]"));
  if (data.targets.dim() != 2 || data.targets.size(0) != m || data.targets.size(1) != config.outputs) {
    return bad(absl::StrCat("targets must be [", m, ", ", config.outputs, "]"));
  }
  for (const torch::Tensor* t : {&data.params, &data.phase, &data.targets}) {
    if (!torch::isfinite(*t).all().item<bool>()) return bad("a non-finite entry");
  }
  return absl::OkStatus();
}

}  // namespace

ParameterizationNetImpl::ParameterizationNetImpl(const ParameterizationNetConfig& config) : config_(config) {
  torch::nn::Sequential mlp;
  int64_t in = config.param_dims + kPhaseFeatures;
  for (int64_t width : config.hidden) {
    mlp->push_back(torch::nn::Linear(in, width));
    mlp->push_back(torch::nn::ReLU());
    in = width;
  }
  mlp->push_back(torch::nn::Linear(in, config.outputs));
  mlp_ = register_module("mlp", mlp);
}

torch::Tensor ParameterizationNetImpl::forward(const torch::Tensor& params, const torch::Tensor& phase) {
  const torch::Tensor angle = (2 * M_PI) * phase;
  // [B, P + 3] -> [B, D]
  const torch::Tensor input = torch::cat({params, phase.unsqueeze(1), angle.sin().unsqueeze(1), angle.cos().unsqueeze(1)}, 1);
  return mlp_->forward(input);
}

absl::StatusOr<torch::Tensor> ParameterizationNetImpl::Trajectory(absl::Span<const double> params, int64_t frames) {
  if (static_cast<int64_t>(params.size()) != config_.param_dims || frames < 2) {
    return absl::InvalidArgumentError(absl::StrCat("parameterization trajectory: ", params.size(), " params (expected ",
                                                   config_.param_dims, ") and ", frames, " frames (expected >= 2)"));
  }
  const torch::Tensor a = torch::tensor(std::vector<double>(params.begin(), params.end()), torch::kFloat32);
  return forward(a.unsqueeze(0).expand({frames, config_.param_dims}), torch::linspace(0, 1, frames));
}

absl::StatusOr<ParameterizationData> EliteTrainingData(const EliteSet& elites) {
  if (elites.size() == 0) return absl::FailedPreconditionError("parameterization data: the elite set is empty");
  if (elites.frames() < 2) return absl::FailedPreconditionError("parameterization data: elites need >= 2 frames");
  std::vector<torch::Tensor> params, targets;
  for (int64_t id : elites.Ids()) {
    const Elite& elite = elites.elite(id);
    params.push_back(torch::tensor(elite.params, torch::kFloat32).unsqueeze(0).expand({elites.frames(), elites.dims()}));
    targets.push_back(elite.trajectory);
  }
  const int64_t n = static_cast<int64_t>(params.size());
  return ParameterizationData{torch::cat(params), torch::linspace(0, 1, elites.frames()).repeat({n}), torch::cat(targets)};
}

absl::StatusOr<double> FitParameterization(ParameterizationNet& net, torch::optim::Optimizer& optimizer,
                                           const ParameterizationData& data, const FitOptions& options) {
  if (options.epochs < 1 || options.minibatch < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("parameterization fit: epochs ", options.epochs, " and minibatch ", options.minibatch, " must be >= 1"));
  }
  if (absl::Status s = CheckData(net->config(), data); !s.ok()) return s;
  at::Generator generator = at::detail::createCPUGenerator(options.seed);
  const int64_t m = data.params.size(0);
  const torch::Tensor params = data.params.to(torch::kFloat32), phase = data.phase.to(torch::kFloat32);
  const torch::Tensor targets = data.targets.to(torch::kFloat32);
  double epoch_loss = 0;
  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    const torch::Tensor order = torch::randperm(m, generator, torch::kLong);
    double loss_sum = 0;
    for (int64_t begin = 0; begin < m; begin += options.minibatch) {
      const torch::Tensor rows = order.slice(0, begin, std::min(m, begin + options.minibatch));
      const torch::Tensor predicted = net->forward(params.index_select(0, rows), phase.index_select(0, rows));
      const torch::Tensor loss = torch::mse_loss(predicted, targets.index_select(0, rows));
      optimizer.zero_grad();
      loss.backward();
      optimizer.step();
      loss_sum += loss.item<double>() * rows.size(0);
    }
    epoch_loss = loss_sum / m;
  }
  return epoch_loss;
}

}  // namespace modskill::learner::family
