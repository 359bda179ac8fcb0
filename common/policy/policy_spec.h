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
#include "common/policy/family_parameters.h"
#include "common/policy/physics_settings.h"
#include "common/policy/reference_frames.h"

namespace modskill {

inline constexpr char kCheckpointSpecFile[] = "modskill/env_spec.json";

// Largest observation or action vector a policy file may declare (the humanoid's are ~1000).
inline constexpr int64_t kMaxPolicyVectorSize = 1 << 20;

// The task of a tracker (SessionConfig.task "" or "tracking"), and what its part controllers read
// beside z when nothing else is recorded (checkpoints from before these fields).
inline constexpr char kTrackingTask[] = "tracking";
inline constexpr char kPartObsControllerInput[] = "part_obs";
inline constexpr char kProprioceptionControllerInput[] = "proprioception";

// The part of the env spec a policy depends on.
struct PolicySpec {
  std::string part_layout;
  int obs_size = 0;
  int action_size = 0;
  std::vector<std::string> joint_names;  // action order
  double control_dt = 0;
  // The physics rate and servos it was trained with; not recorded in policies from before the
  // field, which any server runs.
  PhysicsSettings physics;
  // The action mapping it was trained with; checkpoints from before action modes existed
  // were trained in absolute mode.
  ActionMapping action;
  // The env it drives: "tracking", or a task env ("steer", ...) whose observation is the self
  // features plus the task's goal (EnvSpec.task).
  std::string task = kTrackingTask;
  // What its part controllers read beside z: "part_obs" (the part's whole observation) or
  // "proprioception" (its bodies' self features only; such controllers can be reused by a task
  // policy, learner/skill_library.h).
  std::string controller_input = kPartObsControllerInput;
  // How many upcoming reference frames a tracker observes (reference_frames.h); policies from
  // before the field observed one.
  int reference_frames = 1;
  // A motor-skill family's policy (learner/family/family_export.h): the clip it grew from, that
  // clip's frame count and the ranges its observation normalizes a over (EnvSpec.family). Empty
  // family: a tracking or task policy.
  std::string family_clip;
  int family_frames = 0;
  std::vector<ParamRange> family;

  bool is_family() const { return !family.empty(); }

  std::string ToJson() const;
  // INVALID_ARGUMENT naming the field for anything but a JSON object whose sizes lie in
  // [1, kMaxPolicyVectorSize], control_dt in (0, 10) s, action mapping is valid, task is a
  // lower-case name ([a-z0-9_], 1 to 32 characters) and controller_input part_obs or
  // proprioception, reference_frames in [1, kMaxReferenceFrames] (only a tracker's above 1),
  // physics (when present) valid as PhysicsSettings::FromJson reads it.
  // Absent task and controller_input read as "tracking" and "part_obs". A
  // family's ranges pass ValidateParamRange with no name twice, its clip is named and its
  // frames in [2, 1e6].
  static absl::StatusOr<PolicySpec> FromJson(absl::string_view json);
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_POLICY_SPEC_H_
