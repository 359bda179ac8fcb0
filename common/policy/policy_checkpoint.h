// A trained policy as shipped: a TorchScript module whose forward maps an observation batch
// [N, obs_size] to deterministic actions [N, action_size], with the env spec it was trained on
// stored beside it in the archive (extra file "modskill/env_spec.json", PolicySpec in
// policy_spec.h). The server runs it for rollouts; Python users can torch.jit.load it.
#ifndef MODSKILL_COMMON_POLICY_POLICY_CHECKPOINT_H_
#define MODSKILL_COMMON_POLICY_POLICY_CHECKPOINT_H_

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/policy_spec.h"

namespace torch::jit {
struct Module;
}  // namespace torch::jit

namespace modskill {

// Writes a TorchScript checkpoint of the affine policy actions = clamp(obs W^T + b, -1, 1)
// (W: [action_size, obs_size], b: [action_size], row-major; empty W means zeros). A baseline
// and a fixture: the zero policy holds every joint at its range midpoint.
absl::Status SaveAffinePolicy(const std::string& path, const PolicySpec& spec, const std::vector<float>& weight,
                              const std::vector<float>& bias);
// The same archive as bytes (for Rollout.checkpoint_bytes). With spec.action in residual mode
// the zero policy is the open-loop reference: PD targets = the reference pose.
absl::StatusOr<std::string> AffinePolicyBytes(const PolicySpec& spec, const std::vector<float>& weight,
                                              const std::vector<float>& bias);

// Torch's intra-op threads for every checkpoint of the process.
void SetTorchThreads(int threads);

class PolicyCheckpoint {
 public:
  static absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> LoadFile(const std::string& path);
  static absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> LoadBytes(absl::string_view bytes);
  ~PolicyCheckpoint();

  const PolicySpec& spec() const { return spec_; }
  // obs: [n, obs_size] -> actions: [n, action_size]; errors on bad output shape or values.
  absl::Status Act(const float* obs, int n, float* actions);

 private:
  PolicyCheckpoint() = default;
  std::unique_ptr<torch::jit::Module> module_;
  PolicySpec spec_;
  std::mutex mutex_;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_POLICY_CHECKPOINT_H_
