// Runs a policy on named clips from their first frame and measures how well it tracks them,
// with the metrics of the ModSkill and PHC papers. Knows nothing of torch or gRPC: the policy
// is a function from an observation batch to an action batch.
#ifndef MODSKILL_SERVER_CORE_ENV_ROLLOUT_H_
#define MODSKILL_SERVER_CORE_ENV_ROLLOUT_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/family_measure.h"
#include "server/core/env/humanoid_state.h"

namespace modskill {

struct RolloutOptions {
  TerminationMode termination = TerminationMode::kEvaluation;
  double termination_distance = 0.5;  // m
  ActionMapping action;               // the one the policy was trained with
  int reference_frames = 1;           // tracking: the upcoming reference frames it observes (else 1)
  int max_steps_per_clip = 0;         // 0: the clip's length (goal tasks: TaskEpisodeSteps)
  int num_threads = 1;
  PhysicsOptions physics;
  // A task env instead of tracking: each clip gives the start state (and the base pose of
  // residual actions); its errors are then against that base clip, and normalized_return says
  // how well the task went.
  TaskKind task = TaskKind::kTracking;
  TaskSettings task_settings;
  uint64_t seed = 0;  // the goals' random stream
  // A motor-skill family's policy (its trained ranges, EnvSpec.family) run at one parameter
  // vector a (in units, one per range, inside it): every clip's env is a family env at a. The
  // motions must then hold exactly the family's one clip.
  std::vector<ParamRange> family;
  std::vector<float> family_params;
};

// obs: [num_envs, obs_size] -> actions: [num_envs, action_size].
using PolicyFunction = std::function<absl::Status(const float* obs, int num_envs, float* actions)>;

struct ClipRolloutMetrics {
  std::string clip;
  bool success = false;  // never terminated
  int steps = 0;
  double g_mpjpe_mm = 0;    // mean global body position error
  double mpjpe_mm = 0;      // mean root-relative body position error
  double acc_error_mm = 0;  // mean |acceleration difference|, mm / frame^2
  double vel_error_mm = 0;  // mean |velocity difference|, mm / frame
  std::vector<double> body_error_mm;  // per body, global
  std::vector<double> part_error_mm;  // per part of the layout
  // Success at stricter termination distances: the largest mean body error seen (m), over the
  // bodies evaluation termination watches (vr_tracking: its tracked bodies; otherwise all).
  double worst_mean_body_error = 0;
  // The task's reward terms but energy, summed over the rollout and divided by the steps it
  // could have lasted (Table 4's normalized return: 0 worst, 1 best). Tracking: over the clip's
  // steps.
  double normalized_return = 0;
  // Family rollouts (RolloutOptions.family): what a did physically, the episode's F, the clip
  // frames the time warp played and whether it reached the clip's last frame.
  bool has_family = false;
  FamilyMotionMeasures family;
  double fitness = 0;
  double final_phase = 0;
  bool reached_end = false;
};

// One simulated frame of one clip: the character and its reference (world poses).
struct RolloutFrameView {
  int clip_index = 0;  // into the clip_ids given to RunRollout
  int frame = 0;       // the clip's frame
  const HumanoidState& sim;
  const HumanoidState& ref;
  double mean_body_error = 0;  // m, over the bodies evaluation termination watches
  bool done = false;           // the clip's last frame in this rollout
  bool terminated = false;     // done by termination (not at the clip's end)
  // The skill embeddings the policy acted on from this frame (FrameSkills.z_size floats), or
  // null: without FrameSkills, and on the last frame (no action is taken from it).
  const float* skill_z = nullptr;
};

// Where a policy leaves the skill embeddings z it acted on at its latest call: z_size floats per
// env, [num_envs, z_size] (e.g. [num_envs, parts, embed_dim]), rewritten by every call.
struct FrameSkills {
  const float* z = nullptr;
  int64_t z_size = 0;
};

// Called for every simulated frame of every clip when set, the first frame included. A frame
// is reported once the policy has acted on it (so that its z is known), the last one at once.
using RolloutFrameCallback = std::function<void(const RolloutFrameView&)>;

// Rolls out every clip of `clip_ids` (indices into `motions`) in parallel envs. With
// `frame_skills.z` set, each frame shows the z the policy left there when it acted on it.
absl::StatusOr<std::vector<ClipRolloutMetrics>> RunRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                           const PartLayout& layout,
                                                           std::shared_ptr<const MotionLibrary> motions,
                                                           const std::vector<int>& clip_ids,
                                                           const PolicyFunction& policy, const RolloutOptions& options,
                                                           const RolloutFrameCallback& on_frame = nullptr,
                                                           const FrameSkills& frame_skills = {});

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_ROLLOUT_H_
