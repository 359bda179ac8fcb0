// The env spec a trained policy depends on, as stored in its checkpoint archive (extra file
// "modskill/env_spec.json"). Torch-free, so that the archive's metadata can be read, tested and
// fuzzed without linking torch; policy_checkpoint.h loads the archive around it. The server
// builds one from its env and checks a policy against it in server/core/env/policy_fit.h.
#ifndef MODSKILL_COMMON_POLICY_POLICY_SPEC_H_
#define MODSKILL_COMMON_POLICY_POLICY_SPEC_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/action_mode.h"

namespace modskill {

inline constexpr char kCheckpointSpecFile[] = "modskill/env_spec.json";

// Largest observation or action vector a policy file may declare (the humanoid's are ~1000).
inline constexpr int64_t kMaxPolicyVectorSize = 1 << 20;

// The part of the env spec a policy depends on.
struct PolicySpec {
  std::string part_layout;
  int obs_size = 0;
  int action_size = 0;
  std::vector<std::string> joint_names;  // action order
  double control_dt = 0;
  // The action mapping it was trained with; checkpoints from before action modes existed
  // were trained in absolute mode.
  ActionMapping action;

  std::string ToJson() const;
  // INVALID_ARGUMENT naming the field for anything but a JSON object whose sizes lie in
  // [1, kMaxPolicyVectorSize], control_dt in (0, 10) s and action mapping is valid.
  static absl::StatusOr<PolicySpec> FromJson(absl::string_view json);
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_POLICY_SPEC_H_
