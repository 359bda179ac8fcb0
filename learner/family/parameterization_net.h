// The parameterization network P(a) -> {(d_t, tau_t)} (Lee et al. 2021; DESIGN.md section 4):
// for task parameters a, the displacement d_t of the clip's frame t and its log time step tau_t
// (phi' = phi + exp(tau)), i.e. the edited motion m_a = (m_0 (+) d)(phi). Trained by regression on
// the elites' trajectories; an MLP (2 x 512 in the paper) from (a, phase of the frame) to (d, tau).
#ifndef MODSKILL_LEARNER_FAMILY_PARAMETERIZATION_NET_H_
#define MODSKILL_LEARNER_FAMILY_PARAMETERIZATION_NET_H_

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "learner/family/elite_set.h"

namespace modskill::learner::family {

struct ParameterizationNetConfig {
  int64_t param_dims = 1;                    // P
  int64_t outputs = 1;                       // D = displacement size + 1 (tau)
  std::vector<int64_t> hidden = {512, 512};  // DESIGN.md: value and parameterization nets 2 x 512
};

class ParameterizationNetImpl : public torch::nn::Module {
 public:
  explicit ParameterizationNetImpl(const ParameterizationNetConfig& config);

  // params [B, P] (normalized to [0, 1]), phase [B] (frame / (L - 1), in [0, 1]) -> [B, D].
  // The phase enters as (phase, sin 2 pi phase, cos 2 pi phase): a clip's displacement rises and
  // falls over it, which a small MLP fits faster from a Fourier feature than from a ramp alone.
  torch::Tensor forward(const torch::Tensor& params, const torch::Tensor& phase);
  // [L, D]: the whole trajectory for one parameter vector of P values. INVALID_ARGUMENT for
  // another number of values or frames < 2.
  absl::StatusOr<torch::Tensor> Trajectory(absl::Span<const double> params, int64_t frames);

  const ParameterizationNetConfig& config() const { return config_; }
  // The MLP after the phase features: [B, P + 3] -> [B, D] (family_export.h scripts it).
  const torch::nn::Sequential& mlp() const { return mlp_; }

 private:
  ParameterizationNetConfig config_;
  torch::nn::Sequential mlp_{nullptr};
};
TORCH_MODULE(ParameterizationNet);

// Regression data: one row per (elite or episode, frame).
struct ParameterizationData {
  torch::Tensor params;   // [M, P]
  torch::Tensor phase;    // [M]
  torch::Tensor targets;  // [M, D]
};

// Every elite's every frame. FAILED_PRECONDITION for an empty set or elites of one frame.
absl::StatusOr<ParameterizationData> EliteTrainingData(const EliteSet& elites);

struct FitOptions {
  int epochs = 10;
  int64_t minibatch = 256;
  uint64_t seed = 0;  // the minibatch order
};

// Regression of the network on the data (mean squared error over (d, tau)), `epochs` passes in
// shuffled minibatches. Returns the mean loss of the last epoch. INVALID_ARGUMENT for data whose
// shapes do not match the network or each other, non-finite data, or epochs/minibatch < 1.
absl::StatusOr<double> FitParameterization(ParameterizationNet& net, torch::optim::Optimizer& optimizer,
                                           const ParameterizationData& data, const FitOptions& options);

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_PARAMETERIZATION_NET_H_
