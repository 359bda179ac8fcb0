// What modskill-policy-upgrade does to one policy.pt: a tracker is re-exported with today's script
// (skills() and act_with_z() beside forward, the same weights; policy_export.h), a task policy
// saved again as it is; and a file from before policies recorded their physics gets the physics
// of the server that describes it, which must be the physics it was trained under
// (common/policy/physics_settings.h). A motor-skill family's file is saved again as it is (forward,
// P(a), elites) with the physics of a family session, which is not the server's own.
#ifndef MODSKILL_LEARNER_POLICY_UPGRADE_H_
#define MODSKILL_LEARNER_POLICY_UPGRADE_H_

#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "common/policy/physics_settings.h"
#include "learner/policy_import.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

struct PolicyUpgrade {
  bool rebuilt = false;  // a tracker re-exported with today's script (else a task policy or family re-saved)
  int parts = 0;
  int64_t embed_dim = 0;
  double forward_difference = 0;  // the largest |old forward - new forward| on random observations
  bool physics_added = false;     // the file had no physics record; it now carries `physics`
  PhysicsSettings physics;        // what the written file records
};

// Writes `exported` (read from exported.path) to `out`: a tracker with today's script, a task
// policy's archive unchanged but for its spec. `server_spec` is the server's Describe for the
// policy's part layout: its observation slices, which a tracker's file does not hold, and its
// physics. FAILED_PRECONDITION naming the setting when the file records physics
// other than the server's; INTERNAL when the new forward differs from the old one by more than
// 1e-5. OUT is written only when every check passes (staged beside it, then renamed).
absl::StatusOr<PolicyUpgrade> UpgradePolicy(ExportedPolicy exported, const v1::EnvSpec& server_spec,
                                            const std::string& out);

// Writes the motor-skill family's policy.pt `in` to `out` as it is but for its spec, which now records
// the physics of `family_session_spec`: the spec of a session the server opened for the family's
// clip and ranges (learner/family/family_session.h). INVALID_ARGUMENT when `in` is not a family's
// file or the spec not a family session's; FAILED_PRECONDITION naming the setting when the file
// records other physics; OUT is written only when every check passes.
absl::StatusOr<PolicyUpgrade> UpgradeFamilyPolicy(const std::string& in, const v1::EnvSpec& family_session_spec,
                                                  const std::string& out);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_POLICY_UPGRADE_H_
