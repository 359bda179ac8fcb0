// Everything a training run is configured with; written into every checkpoint.
#ifndef MODSKILL_LEARNER_TRAINER_CONFIG_H_
#define MODSKILL_LEARNER_TRAINER_CONFIG_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/policy/action_mode.h"
#include "common/policy/termination.h"
#include "learner/data_parallel_options.h"
#include "learner/model_config.h"

namespace modskill {
enum class TerminationBodies;  // server/core/env/tracking_env.h
}  // namespace modskill

namespace modskill::learner {

// The sessions' SessionConfig.imitation_kernels (the imitation reward's k per term); 0 in a field:
// the server's default (PHC's 100, 10, 0.1, 0.1).
struct ImitationKernels {
  double pos = 0, rot = 0, vel = 0, ang_vel = 0;
  bool any() const { return pos != 0 || rot != 0 || vel != 0 || ang_vel != 0; }
};

// "--imitation_kernels pos=400,rot=20" (terms pos, rot, vel, ang_vel, each once, in [0, 10000]);
// "": every term's default. INVALID_ARGUMENT naming the flag and the part that is wrong.
absl::StatusOr<ImitationKernels> ParseImitationKernels(absl::string_view text);
std::string ImitationKernelsText(const ImitationKernels& kernels);  // "pos=400,rot=20", "" for defaults

struct TrainerConfig {
  // Where to simulate.
  std::vector<std::string> servers;
  std::string token;
  std::string tls_ca_file;
  int envs_per_server = 256;
  int sessions_per_server = 2;      // two halves per server overlap simulation with inference
  std::string part_layout = "5part";
  std::vector<std::string> motions;  // clip names; empty: the server's whole library
  double server_timeout_s = 120;     // exit when no server answers for this long

  // How actions drive the PD targets and when training episodes fail (see ../server/core/
  // action_mapping.h and tracking_env.h).
  std::string action_mode = "residual";  // absolute | residual
  double residual_scale = 0.5;
  double termination_distance = 0.25;      // m, any watched body farther than this fails
  // Small preset: PHC's no_feet (bench/learning_bench.sh on deepmimic_walk, 0.49 M steps:
  // eval Succ 100 % and E_mpjpe 64 mm against 0 % and 95 mm watching every body).
  std::string termination_bodies = "no_feet";  // all | no_feet
  // A termination curriculum (both > 0): the distance starts at curriculum_start and moves
  // toward curriculum_end as more episodes track their clip to the end (see
  // termination_curriculum.h); termination_distance is then unused.
  double curriculum_start = 0, curriculum_end = 0;
  // Torch threads for the PPO and discriminator updates, while the servers wait (0: keep the
  // collection's).
  int update_threads = 2;
  // Collect the next batch while the update runs, acting with the weights from before the update
  // (a policy lag of one update; PPO's ratios are taken against those behaviour weights). Pays off
  // when the servers run on other machines; on one 2-core machine both phases share the cores.
  // The update then keeps the collection's torch threads (update_threads is not used).
  bool collect_during_update = false;

  // Skill reuse (issue 13): a task other than "tracking" ("steer", "reach", "strike",
  // "vr_tracking"; the server lists its tasks in Describe) trains a high-level policy that drives
  // the frozen part controllers of the tracker in `skills` (its exported policy.pt, trained with
  // --controller_input proprioception). The task session then runs the tracker's action mapping.
  std::string task = "tracking";
  std::string skills;
  // Tracking from an exported tracker (part_retraining.h): its policy.pt, and the parts that train
  // (empty: all); the other parts' controllers and attention maps stay frozen.
  std::string init_from;
  std::vector<std::string> train_parts;
  bool train_attention = true;  // with train_parts: their attention maps train too
  bool fresh_parts = false;      // with train_parts: they start from fresh weights, not the tracker's
  // SessionConfig.reward_parts: the imitation reward averages over these parts' bodies only (empty:
  // every body), e.g. the retrained parts, whose signal the frozen parts' errors would drown.
  std::vector<std::string> reward_parts;
  // SessionConfig.reward_relative_to_root: the rewarded bodies are compared in the root's frame,
  // so the root's drift (the frozen legs') stays out of the retrained parts' reward.
  bool reward_relative_to_root = false;
  // With train_parts: the frozen parts act on their means (no exploration noise, no share in PPO's
  // ratios), as they will in evaluation.
  bool frozen_parts_act_on_mean = false;
  // Tracking: clips loop (SessionConfig.loop_clips), so that episodes run 300 steps through the
  // clip's seams, as a task's looping base motion later asks of the skills.
  bool loop_clips = false;
  // Tracking: the reference is carried onto the character each step (SessionConfig.anchor_reference),
  // as a task's base motion will be: the skills learn to go on from where they are, not to win
  // back drift.
  bool anchor_reference = false;
  // With anchor_reference: the root's position only; the reference keeps the clip's heading, so a
  // heading error stays until won back (SessionConfig.anchor_position_only): skills that follow a
  // base motion a goal task steers (--task_steering_rate).
  bool anchor_position_only = false;
  // Tracking: the upcoming reference frames each body observes (SessionConfig.reference_frames,
  // MimicKit's tar_obs_steps 1..N); not with loop_clips or anchor_reference.
  int reference_frames = 1;
  // Given on the command line (a resume without it takes the checkpoint's count).
  bool reference_frames_given = false;
  // SessionConfig.task_settings; 0 in a field: the server's default.
  double task_min_speed = 0, task_max_speed = 0, task_min_goal_interval_s = 0, task_max_goal_interval_s = 0;
  // reach's target box: its edge (m; 0: the server's 2 m) and its centre, forward, left, height
  // (empty: the server's (0, 0, 1)).
  double task_reach_box_size = 0;
  std::vector<double> task_reach_center;
  // steer, reach, strike: the base motion turns toward the goal at up to this rate (deg/s; 0:
  // straight on, the paper's), so that skills trained on turning clips read the turn from it.
  double task_steering_rate = 0;
  // The parts whose z the task head displaces (e.g. R_Arm for reach); the others play the skill
  // prior's z exactly, without exploration noise, and leave PPO's ratios. Empty: every part (the
  // paper's high level). Needs the skill prior (a part without a head has no other z).
  std::vector<std::string> task_parts;
  // Reach only: a teacher table of held reach poses (reach_teacher.h, bench/reach_teacher.py) whose
  // nearest entry's z the PPO update pulls the head's mean z toward, with task_teacher_weight
  // falling linearly to 0 over task_teacher_steps env steps (0: held). Empty: no teacher.
  std::string task_teacher;
  double task_teacher_weight = 1.0;
  int64_t task_teacher_steps = 0;

  // What to learn with.
  ModelConfig model;
  int iterations = 100;
  int horizon = 32;             // steps per env per iteration (PHC)
  // Small preset: 1 epoch and 1 discriminator epoch. The update runs on the cores the servers
  // step on, so its cost per sample bounds end-to-end throughput (bench/learner_throughput_bench:
  // 5 + 2 epochs gave 0.24 x the server alone, 2 + 1 0.51 x, 1 + 1 0.60 x, medians); with ~80 % of
  // the ratios clipped, a second pass over the batch learned no more per sample on the walk
  // (README, "Learning").
  int epochs = 1;
  int minibatch_size = 2048;
  // Small preset. With sigma = exp(-2.9) PPO's ratios are steep: with one epoch 1e-4 clips ~10 %
  // of the samples (KL ~0.007) and 2e-4 ~22 % (KL ~0.018, a little closer tracking on the walk;
  // README, "Learning": closer in three seeds of three); 3e-4 with 5 epochs diverged (KL ~ 30).
  // The paper's 2e-5 suits its 3072-env GPU batches.
  double learning_rate = 2e-4;
  // Linear decay of learning_rate to learning_rate x learning_rate_floor over this many env steps
  // (learning_rate_decay.h); 0: constant.
  int64_t learning_rate_decay_steps = 0;
  double learning_rate_floor = 0.1;
  // The critic's own Adam step size (ProtoMotions: actor 2e-5, critic 1e-4); it decays with
  // learning_rate. 0: the critic shares learning_rate (one parameter group, as before). The small
  // preset's tracking runs take 1e-3 (kSmallTrackingCriticLearningRate).
  double critic_learning_rate = 0;
  // --critic_learning_rate was given: a resumed checkpoint must have its optimizer groups.
  // Otherwise a resumed run goes on at its checkpoint's critic rate (0 before the flag).
  bool critic_learning_rate_given = false;
  double gamma = 0.99;
  double lambda = 0.95;
  // --gamma / --lambda were given: otherwise a resumed run goes on with its checkpoint's (0.99 and
  // 0.95 in checkpoints from before they were stored).
  bool gamma_given = false, lambda_given = false;
  double clip_ratio = 0.2;
  double value_clip = 0.2;
  double value_coefficient = 2.0;
  // The critic predicts returns normalized by their running statistics (critic.h; rl_games'
  // normalize_value, on in AMP's, ASE's and PHC's configs).
  bool normalize_value = false;
  double max_grad_norm = 1.0;
  double task_reward_weight = 0.5;  // PHC: task and AMP rewards 0.5 / 0.5
  double amp_reward_weight = 0.5;
  // The sessions' SessionConfig.energy_weight: the server's energy penalty as a multiple of the
  // paper's (1: left unset on the wire, so family sessions, which have none, accept it). A goal
  // task over frozen skills pays about 0.03 per step for reaching while the penalty costs about
  // 0.12, so every step lived is negative and PPO learns to fall (reach, 2026-12-04); 0 keeps each
  // step's reward >= 0. Evaluation's normalized return never counts energy.
  double energy_weight = 1.0;
  ImitationKernels imitation_kernels;
  // Each env keeps its exploration noise for this many control steps on average (geometric;
  // held_noise.h), and draws afresh when its episode ends; 1: fresh noise every step.
  int noise_hold_steps = 1;
  double discriminator_learning_rate = 1e-4;
  double gradient_penalty_weight = 5.0;
  int discriminator_epochs = 1;
  int amp_samples = 2048;  // expert and policy samples per discriminator epoch
  // --amp_frames was given: a resumed checkpoint must have been trained with model.amp_frames.
  // Otherwise a resumed run reads as many frames as its checkpoint's discriminator did.
  bool amp_frames_given = false;
  uint64_t seed = 1;
  int report_every = 5;  // iterations between failure reports to the servers' samplers; 0: never

  // Data-parallel learners (data_parallel.h): this learner's rank among world_size, each driving
  // its own servers; rank 0 alone writes to run_dir.
  DataParallelOptions data_parallel;

  // Where results go.
  std::string run_dir;
  int checkpoint_every = 10;  // iterations
  bool resume = false;

  static absl::StatusOr<TrainerConfig> ForPreset(const std::string& preset);
  absl::Status Validate() const;
  std::string ToJson() const;
};

// Whether episodes of `task` follow clips, so that their failures mean something to the server's
// clip sampler (ReportFailures): tracking and vr_tracking.
bool TaskFollowsClips(const std::string& task);
bool IsTrackingTask(const std::string& task);
// On the walk the median of 30 exports tracked 0-7.7 mm closer at four seeds of four, never
// further (README, Performance, "Learning").
inline constexpr double kSmallTrackingCriticLearningRate = 1e-3;
// DeepMimic's discount: on the walk the median of 30 exports tracked 26.6 / 26.2 mm against
// 40.3 / 34.8 mm with 0.99, two seeds of two (README, Performance, "Learning").
inline constexpr double kSmallTrackingGamma = 0.95;

// INVALID_ARGUMENT naming --task and what `server` offers unless `described` (its Describe
// answer) lists `task`.
absl::Status CheckTaskOffered(const v1::EnvSpec& described, const std::string& task, const std::string& server);

// The sessions' task settings from a validated config: each 0 or empty field left to the server.
void WriteTaskSettings(const TrainerConfig& config, v1::TaskSettings* settings);

// The action mode and the watched bodies of a validated config.
ActionMode ActionModeOf(const TrainerConfig& config);
TerminationBodies TerminationBodiesOf(const TrainerConfig& config);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TRAINER_CONFIG_H_
