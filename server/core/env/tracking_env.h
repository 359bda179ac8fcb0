// One humanoid tracking one reference clip: reference state initialization, PD control,
// imitation reward, termination, truncation and automatic reset. Writes its row of the batch.
// With a task (EnvSpec::task) the same humanoid starts from a reference state and then pursues
// the task: steer and reach reward their goal and end at a fall, VR tracking observes only the
// head and hands of the reference. The clip keeps playing under a goal task (looping at its end)
// as the base pose of residual actions.
#ifndef MODSKILL_SERVER_CORE_ENV_TRACKING_ENV_H_
#define MODSKILL_SERVER_CORE_ENV_TRACKING_ENV_H_

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/policy/termination.h"
#include "server/core/curriculum/clip_sampler.h"
#include "server/core/env/action_mapping.h"
#include "server/core/env/base_motion_anchor.h"
#include "server/core/env/batch_buffers.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/episode_end.h"
#include "server/core/env/family_episode.h"
#include "server/core/env/fall_detection.h"
#include "server/core/env/goal_task.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/env/imitation_reward.h"
#include "server/core/env/reference_amp.h"
#include "server/core/motion/motion_library.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/pd_controller.h"

namespace modskill {

enum class TerminationMode {
  kTraining,    // any body farther than `termination_distance` (0.25 m) from its reference
  kEvaluation,  // mean body distance above `termination_distance` (0.5 m)
  kNone,        // only truncation at the clip's end
};

struct TrackingEnvConfig {
  TerminationMode termination = TerminationMode::kTraining;
  double termination_distance = 0.25;  // m
  TerminationBodies termination_bodies = TerminationBodies::kAll;  // kTraining only
  ActionMapping action;
  ImitationRewardConfig reward;
  int max_episode_steps = 0;  // 0: until the clip ends (goal tasks: TaskEpisodeSteps)
  TaskKind task = TaskKind::kTracking;
  TaskSettings task_settings;
  bool random_start_frame = true;
  // Tracking: the clip loops (SessionConfig.loop_clips); episodes end at TaskEpisodeSteps.
  bool loop_clips = false;
  // Tracking: the reference is carried onto the character's root and heading each step, as a goal
  // task's base motion is (SessionConfig.anchor_reference).
  bool anchor_reference = false;
  // With anchor_reference: the root's position only; the reference keeps the clip's own heading
  // (SessionConfig.anchor_position_only).
  bool anchor_position_only = false;
  // Plain tracking (no loop, no anchor, no family): the upcoming reference frames each observation
  // holds (SessionConfig.reference_frames); the ones past the clip's end repeat its last frame.
  int reference_frames = 1;
  // A motor-skill family (family_episode.h): the session's parameter ranges; empty otherwise.
  std::vector<ParamRange> family;
  // false: an ended episode keeps its final state and later steps do nothing until the next
  // reset (rollouts and evaluation).
  bool auto_reset = true;
};

// The shared, read-only context of a batch of envs.
struct EnvContext {
  std::shared_ptr<const HumanoidModel> humanoid;
  std::shared_ptr<const EnvSpec> spec;
  std::shared_ptr<const MotionLibrary> motions;
  // The id an env reports for library clip i (clip_id, ended_clip_id): clip_ids[i], or i itself
  // when empty. Sessions whose motion set changes keep ids stable while library indices move.
  std::vector<int> clip_ids;
  const ClipSampler* sampler = nullptr;
  std::shared_ptr<const ReferenceAmpFrames> reference_amp;
  TrackingEnvConfig config;
  // The bodies training termination watches (config.termination_bodies; VR tracking: the head
  // and hands), spec order.
  std::vector<int> termination_body_ids;
  std::vector<int> vr_body_ids;  // vr_tracking's TaskInfo::tracked_bodies, spec indices
  GoalTaskContext goal_task;
  std::shared_ptr<const FallDetector> fall_detector;
  std::shared_ptr<const FamilyContext> family;  // family sessions only
};

// Where env i writes in a BatchBuffers.
struct EnvRow {
  BatchBuffers* buffers;
  int index;
};

class TrackingEnv {
 public:
  TrackingEnv(const EnvContext* context, uint64_t seed);
  ~TrackingEnv();
  TrackingEnv(const TrackingEnv&) = delete;
  TrackingEnv& operator=(const TrackingEnv&) = delete;

  // New episode on a sampled clip and start frame; writes the row's observation.
  void Reset(EnvRow row);
  // New episode on library clip `clip` at `frame` (tests, rollouts).
  void ResetTo(int clip, int frame, EnvRow row);
  // One control step with `action` (action_size values, part order, in [-1, 1]).
  void Step(const float* action, EnvRow row);

  const mjData* data() const { return data_; }
  mjData* mutable_data() { return data_; }
  // The reported id of the episode's clip (see EnvContext::clip_ids).
  int clip() const { return clip_; }
  int frame() const { return frame_; }
  // The clip the episode tracks (a family at other body proportions: the clip on its skeleton).
  const MotionClip& motion() const { return *motion_; }
  // With auto_reset off: the episode has ended and the env waits for a reset.
  bool finished() const { return finished_; }
  int64_t physics_resets() const { return physics_resets_; }
  // The PD targets of the last step (one per hinge, radians), as the servos got them.
  const std::vector<double>& pd_targets() const { return pd_targets_; }
  // Reward terms and errors of the current state against the reference at the current frame.
  TrackingErrors CurrentTrackingTerms(float* terms);
  // Family sessions: the parameters a of this env's next episode (one per range, inside it).
  void SetNextFamilyParameters(const float* a) { family_->SetNext(a); }
  // nullptr outside a family session.
  const FamilyEpisode* family() const { return family_.get(); }
  // Rewrites the row's observation from qpos/qvel (after external changes to the state, such
  // as a push).
  void RefreshObservation(EnvRow row);

 private:
  void WriteObservation(EnvRow row);
  void EndEpisode(EnvRow row);
  // The phases of Step after the physics: a blow-up, a tracking step, a goal task's step.
  void EndOnBlowUp(EnvRow row);
  // A family session's step (tracking_env_family.cc): the time warp moves the phase, the
  // reference there is displaced by the action, the task scores its peaks.
  void StepFamily(const float* action, EnvRow row);
  void WriteFamilyObservation(float* obs, EnvRow row);
  TrackingErrors ScoreTracking(float* terms, EnvRow row);
  void ScoreGoalTask(float* terms, EnvRow row);
  // The energy term (last column) and the reward, their sum.
  void AddEnergyAndSum(double power, float* terms, EnvRow row) const;
  // Books the episode's end if `failure` names one (kNone: none) or the step limit (or the clip's
  // end) is reached; otherwise pushes the AMP frame and writes the next observation.
  void FinishStep(EpisodeEnd failure, bool at_end, EnvRow row);
  // The reference frame the next step reaches: tracking stops at the clip's end, goal tasks and
  // looping clips go on at frame 1.
  int NextFrame() const;
  bool LoopsClip() const { return context_->config.loop_clips && goal_task_ == nullptr; }
  bool AnchorsReference() const {
    return context_->config.anchor_reference && goal_task_ == nullptr && family_ == nullptr;
  }
  // A goal task whose base motion turns toward the goal (TaskSettings::steering_rate).
  bool SteersBaseMotion() const { return goal_task_ != nullptr && context_->goal_task.settings.steering_rate > 0; }
  // Whether loop_motion_ carries the reference: a loop's cycles, or the anchor onto the character.
  bool MovesReference() const { return LoopsClip() || AnchorsReference(); }
  // Where the reference of `frame`, the next frame or the current one, lies in this loop (the
  // next cycle's when `frame` wrapped).
  PlanarMotion LoopMotionOf(int frame) const;
  // Errors over the VR bodies only (VR tracking's success and errors).
  TrackingErrors VrErrors() const;
  // The row's max, mean and per-part body errors (body_distance_ holds this step's distances).
  void WriteErrors(const TrackingErrors& errors, EnvRow row) const;
  // Mean body distance per part of the layout between sim_ and reference_ (one float per part).
  void WritePartErrors(float* part_error) const;
  bool PhysicsDiverged() const;
  // Whether the state just reached (sim_ against reference_) ends the episode as a failure.
  bool Terminated(const TrackingErrors& errors) const;

  const EnvContext* context_;
  std::unique_ptr<GoalTask> goal_task_;  // steer, reach; nullptr otherwise
  std::unique_ptr<FamilyEpisode> family_;  // family sessions; nullptr otherwise
  mjData* data_;
  PdController pd_;
  std::mt19937_64 rng_;
  // The episode's clip, held so that the library can be replaced between steps (generated clips
  // joining or leaving) without disturbing an episode in progress.
  std::shared_ptr<const MotionClip> motion_;
  // Whose skeleton the simulated state is read with: the session's humanoid, or a family
  // episode's at other body proportions.
  const HumanoidModel* kinematics_ = nullptr;
  int clip_ = 0;
  // A looping clip: where the current cycle's reference lies, and the clip's own displacement per
  // cycle. An anchored reference: the motion that put this step's frame on the character.
  PlanarMotion loop_motion_, cycle_motion_;
  int frame_ = 0;
  // A steered base motion's heading (rad, world yaw; SteerHeading).
  double base_heading_ = 0;
  // A reference anchored in position only: the yaw (rad) its heading has turned from the clip's
  // own, a looping clip's cycle yaw once per cycle.
  double reference_yaw_ = 0;
  int episode_steps_ = 0;
  bool finished_ = false;
  int64_t physics_resets_ = 0;
  // Preallocated scratch so that Step never allocates.
  HumanoidState sim_, reference_, target_, upcoming_;
  std::vector<double> pd_targets_;
  std::vector<double> body_distance_;  // this step's per-body distance to the reference (m)
  std::vector<float> amp_history_;  // ring of kAmpHistory frames
  int amp_head_ = 0;                // index of the newest frame
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_TRACKING_ENV_H_
