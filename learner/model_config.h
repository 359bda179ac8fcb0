// Sizes of the learner's networks (ModSkill, Huang, Dou, Liu 2025) and the slices of the
// observation and action that belong to each body part.
#ifndef MODSKILL_LEARNER_MODEL_CONFIG_H_
#define MODSKILL_LEARNER_MODEL_CONFIG_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

struct ModelConfig {
  std::string preset = "small";
  std::vector<int64_t> attention_hidden;   // per-part key/query/value maps: part obs -> hidden... -> embed_dim
  int64_t embed_dim = 32;                  // skill embedding z (paper: 64)
  std::vector<int64_t> controller_hidden;  // per-part low-level controller MLP
  std::vector<int64_t> critic_hidden;
  std::vector<int64_t> discriminator_hidden;
  double log_std = -2.9;    // fixed Gaussian sigma = exp(-2.9) (PHC)
  // Frames of the server's AMP history (newest first) the discriminator reads; 0: all of them (the
  // paper's 10). AMP's own discriminator reads 2 (s, s'); each frame costs the discriminator's
  // first layer, the update's most expensive matrix.
  int64_t amp_frames = 0;
  bool whole_body = false;  // ablation: one controller for the whole body (input: all z concatenated + full obs)
  bool attention = true;    // ablation: false -> each part's z comes from its own value map only (attention = identity)
  // What a part's controller reads beside z_k: the part's whole observation (proprioception and
  // the reference features) or its proprioception only, so that the reference reaches it only
  // through z and a high-level policy can drive the frozen controllers with its own z (skill
  // reuse; PULSE's and ASE's low levels read proprioception and the latent only).
  enum class ControllerInput { kPartObservation, kProprioception };
  ControllerInput controller_input = ControllerInput::kPartObservation;
  // Skill reuse (a layout with a goal): the high-level policy's MLP from the task observation to
  // one z per part (paper: {2048, 1024, 512}), and its fixed Gaussian log sigma in z space.
  std::vector<int64_t> task_hidden;
  double task_log_std = -2.9;
  // Skill reuse over a prior (PULSE's and CALM's residual over a learned prior): where the task
  // observes its base motion as a tracker observes a reference (steer, reach, strike), the
  // tracker's frozen skill attention maps it to z_prior, and the task head's output is a
  // displacement: z = normalize(z_prior + task head). A zero displacement plays the base motion
  // with the tracker's own skills; exploration starts from there. Off: z = normalize(task head),
  // the paper's high level.
  bool task_skill_prior = true;

  // "paper": attention {256} -> 64, controllers {2048,1536,1024,512}, critic {2048,1536,1024,512},
  //          discriminator {1024,512} over all 10 AMP frames, task head {2048,1024,512}.
  // "small" (fits a 2-core CPU): attention {64} -> 32, controllers {256,128}, critic {256,128},
  //          discriminator {256,128} over the newest 2 AMP frames, task head {256,128}.
  // INVALID_ARGUMENT naming the preset otherwise.
  static absl::StatusOr<ModelConfig> Preset(absl::string_view name);

  // This config with the tracking policy's shape taken from `policy` (attention maps, embedding,
  // controllers and what they read, sigma, the ablations); the critic's, discriminator's and task
  // head's settings stay. A run that starts from another policy (--init_from) records the
  // networks it actually built.
  ModelConfig WithPolicyShapeOf(const ModelConfig& policy) const;
};

// "part_obs" or "proprioception" (--controller_input); INVALID_ARGUMENT naming the value otherwise.
absl::StatusOr<ModelConfig::ControllerInput> ParseControllerInput(absl::string_view name);
const char* ControllerInputName(ModelConfig::ControllerInput input);

struct PartSlices {
  std::string name;
  int64_t obs_start = 0, obs_size = 0, action_start = 0, action_size = 0;
  // The part's proprioceptive features: (start, size) per body, inside the part's obs slice.
  std::vector<std::pair<int64_t, int64_t>> self_obs;
  int64_t self_obs_size() const;
};

struct NetworkLayout {
  int64_t obs_size = 0, action_size = 0, amp_obs_size = 0;
  // The server's AMP observation: amp_history frames of amp_obs_per_frame floats, newest first.
  // amp_obs_size is what the discriminator reads: the newest frames, as ReadAmpFrames sets it.
  int64_t amp_history = 0, amp_obs_per_frame = 0;
  int64_t wire_amp_obs_size() const { return amp_history * amp_obs_per_frame; }
  std::vector<PartSlices> parts;  // contiguous, in order; obs and action slices each tile [0, size)
  // The env's task (EnvSpec.task; "tracking" where the server sends none). In a task env the
  // goal follows the parts' obs slices (which hold their bodies' self features, and in steer,
  // reach and strike also the anchored base motion's reference features, as in tracking):
  // obs = [parts | goal], goal = [goal_start, goal_start + goal_size); goal_size 0 in tracking.
  std::string task = "tracking";
  int64_t goal_start = 0, goal_size = 0;
  bool has_goal() const { return goal_size > 0; }
  // Where the parts' obs slices end: goal_start with a goal, obs_size without.
  int64_t parts_obs_end() const { return has_goal() ? goal_start : obs_size; }
  // INVALID_ARGUMENT unless obs_size, action_size and every part's slices are > 0 (amp_obs_size
  // >= 0: 0 means no discriminator), the parts' obs slices tile [0, parts_obs_end()) and their
  // action slices [0, action_size) in part order, and a goal ends at obs_size. The message names
  // the part (or the goal).
  absl::Status Validate() const;
};

// The layout of the env's observation and action as the server describes it (EnvSpec.parts);
// check it with Validate before building networks on it.
NetworkLayout LayoutFromWireSpec(const v1::EnvSpec& spec);

// Sets layout->amp_obs_size to the newest `frames` of the server's AMP history (0: all of them);
// INVALID_ARGUMENT naming --amp_frames when frames is negative or above the server's history.
absl::Status ReadAmpFrames(int64_t frames, NetworkLayout* layout);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_MODEL_CONFIG_H_
