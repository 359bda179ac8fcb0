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
#include "absl/types/span.h"
#include "common/policy/family_elites.h"
#include "common/policy/policy_spec.h"

namespace torch::jit {
struct Module;
}  // namespace torch::jit
namespace at {
class Tensor;
}  // namespace at

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

// The largest exported policy file any reader loads (the paper preset's are a few hundred MB).
inline constexpr size_t kMaxPolicyFileBytes = size_t{2} << 30;

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

  // Skill composition. A ModSkill policy exported since issue 13 (learner/policy_export.h) also
  // defines skills(obs) -> z [n, P, E] and act_with_z(obs, z) -> actions; older archives and
  // affine policies do not (has_skills() false, and the two calls FAILED_PRECONDITION); nor does
  // one whose skills() fails on a zero observation (skills_error() says why; forward still runs).
  bool has_skills() const { return skill_parts_ > 0; }
  const absl::Status& skills_error() const { return skills_error_; }
  int skill_parts() const { return skill_parts_; }
  int embed_dim() const { return embed_dim_; }
  // Per-part controllers (not the whole-body ablation's one controller, whose input mixes every
  // part's z).
  bool has_part_controllers() const { return part_controllers_; }
  // obs: [n, obs_size] -> z: [n, skill_parts, embed_dim].
  absl::Status Skills(const float* obs, int n, float* z);
  // obs: [n, obs_size], z: [n, skill_parts, embed_dim] -> actions: [n, action_size].
  absl::Status ActWithZ(const float* obs, const float* z, int n, float* actions);

  // A motor-skill family's policy (spec().is_family(); learner/family/family_export.h): its elite
  // set (kCheckpointFamilyElitesFile, empty without one) and the parameterization network P(a),
  // the method parameterization(a [n, P] normalized to [0, 1], phase [n] in [0, 1]) -> [n, D].
  const std::vector<FamilyEliteRecord>& family_elites() const { return family_elites_; }
  bool has_parameterization() const;
  // P(a) over the clip's frames: [spec().family_frames, action_size], row-major, at the
  // normalized parameters u (one per range). FAILED_PRECONDITION without the method.
  absl::StatusOr<std::vector<float>> Parameterization(absl::Span<const double> u);

 private:
  PolicyCheckpoint() = default;
  // Finds skills()' output shape by running it on one zero observation (no methods: stays 0).
  absl::Status ProbeSkills();
  absl::Status NoSkills() const;
  absl::Status CopyOut(const char* method, const at::Tensor& output, int n, int64_t row_size, float* out);
  std::unique_ptr<torch::jit::Module> module_;
  PolicySpec spec_;
  int skill_parts_ = 0, embed_dim_ = 0;
  absl::Status skills_error_;
  bool part_controllers_ = false;
  std::vector<FamilyEliteRecord> family_elites_;
  std::mutex mutex_;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_POLICY_CHECKPOINT_H_
