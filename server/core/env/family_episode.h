// One env's episode of a motor-skill family (Lee et al. 2021; DESIGN.md section 4; issue 14):
// the task parameters a of the episode and what they change in the env's own copy of the model
// (gravity, masses, the obstacle), the time-warped phase, the task's spike reward at a peak, and
// the episode's fitness F. TrackingEnv owns one per env in a family session.
//
// What each parameter does:
//   gravity            opt.gravity = (0, 0, -g)
//   body_mass_scale    every body's mass and inertia times s
//   jump_height        at the jump's apex (the root's vertical velocity turning from up to down
//                      above its start height + 5 cm) a spike kSpikeWeight exp(-(z - a)^2 / s^2)
//                      with s = kPeakSigma; default: the clip's own apex
//   target_height      the same at the apex of the highest end effector (ankles, wrists) once it
//                      is 20 cm above its start; default: the clip's own highest effector
//   obstacle_height    a static box across the clip's start heading, 2 m wide, 10 cm deep;
//   obstacle_distance  its distance from the start root; defaults 0.1 m and half the clip's travel
//   leg_scale          the legs' lengths and radii (family_body_models.h), and the reference: the
//   arm_scale          clip on the scaled skeleton, its root's travel scaled by leg_scale
// r_constraint (the fitness's constraint term) is the product of the episode's constraint
// rewards (each peak's exp term; the obstacle: 1 untouched, 0 touched), 0 for none.
#ifndef MODSKILL_SERVER_CORE_ENV_FAMILY_EPISODE_H_
#define MODSKILL_SERVER_CORE_ENV_FAMILY_EPISODE_H_

#include <memory>
#include <random>
#include <vector>

#include <mujoco/mujoco.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "common/policy/action_mode.h"
#include "common/policy/family_fitness.h"
#include "common/policy/family_parameters.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/family_body_models.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

inline constexpr double kFamilySpikeWeight = 10.0;  // the paper's spike task weight
inline constexpr double kFamilyPeakSigma = 0.1;     // m
inline constexpr double kFamilyTimeWeight = 0.16;   // r_time's share beside tracking's terms
inline constexpr double kFamilyTimeSigma = 0.1;     // r_time = exp(-(dphi - 1)^2 / sigma)
inline constexpr double kFamilyDefaultTerminationDistance = 1.0;  // m: a family moves off its clip

// What the envs of a family session share: the ranges, where each parameter sits in a, the
// obstacle, the feet and effectors, and the clip's own values.
struct FamilyContext {
  std::vector<ParamRange> ranges;
  // Index into a of each parameter, -1 when the session does not vary it.
  int gravity = -1, body_mass_scale = -1, jump_height = -1, target_height = -1;
  int obstacle_height = -1, obstacle_distance = -1;
  int leg_scale = -1, arm_scale = -1;
  // The scaled humanoids, with leg_scale or arm_scale; null otherwise.
  std::shared_ptr<FamilyBodyModels> body_models;
  int obstacle_geom = -1;               // MuJoCo geom id; -1 without obstacle parameters
  std::vector<char> humanoid_geom;      // per MuJoCo geom: a body of the humanoid's
  std::vector<int> feet;                // spec body indices
  // Per hinge, N*m: the paper's torque limits by joint group (FamilyTorqueLimits).
  std::vector<double> hinge_torque_limit;
  std::vector<double> foot_contact_height;  // per foot: in contact below it (the clip's start + 3 cm)
  std::vector<int> effectors;           // ankles and wrists, spec body indices
  double root_start_height = 0, root_apex_height = 0;  // the clip's
  double effector_start_height = 0, effector_peak_height = 0;
  double travel = 0;                    // m, horizontal root displacement over the clip
  double control_dt = 0;                // s, one control step (the physics substeps it holds)
};

// The ranges this server can run: the catalog's checks (ValidateParamRange) and no name twice.
// INVALID_ARGUMENT naming the parameter, under `field`.
absl::Status ValidateFamilyRanges(absl::Span<const ParamRange> ranges, absl::string_view field);
// The catalog entries this server offers (Describe).
std::vector<FamilyParameterInfo> OfferedFamilyParameters();
bool FamilyNeedsObstacle(absl::Span<const ParamRange> ranges);
// Everything a family session needs besides its clip's content, checked once for the service's
// SessionConfig and for EnvBatch: ValidateFamilyRanges under `ranges_field`, exactly one clip,
// task tracking, residual actions, no looping. INVALID_ARGUMENT naming the field.
absl::Status ValidateFamilySession(absl::Span<const ParamRange> ranges, absl::string_view ranges_field, int clips,
                                   TaskKind task, ActionMode action_mode, bool loop_clips);

// The context of a family session over its one clip (ranges checked: ValidateFamilySession);
// `humanoid` must hold the obstacle geom when FamilyNeedsObstacle.
absl::StatusOr<std::shared_ptr<const FamilyContext>> MakeFamilyContext(std::vector<ParamRange> ranges,
                                                                       std::shared_ptr<const HumanoidModel> humanoid,
                                                                       const MotionClip& clip);

// A tracking spec made a family's: goal_obs = [a normalized | phase / last frame], one more
// action (the time warp, last), and the reward terms pos, rot, vel, ang_vel, time, task, energy.
void AddFamilyToSpec(const std::vector<ParamRange>& ranges, EnvSpec* spec);

// Per hinge (spec order), N*m: Lee et al.'s Table 3 limits by joint group, scaled by
// character_mass (kg) over their character's 61.7 kg.
std::vector<double> FamilyTorqueLimits(const HumanoidSpec& spec, double character_mass);

// The time warp of the paper's code: the phase advances exp(clip(1.5 tau, -2, 1)) frames.
double PhaseStep(float tau);

struct FamilyStepScore {
  float time_reward = 0;  // continuous: kFamilyTimeWeight r_time
  float spike = 0;        // the task's one-off reward at a peak
};

class FamilyEpisode {
 public:
  // Copies `base` (the session's model) once; episodes then write their parameters into the copy.
  FamilyEpisode(const FamilyContext* family, const mjModel* base);
  ~FamilyEpisode();
  FamilyEpisode(const FamilyEpisode&) = delete;
  FamilyEpisode& operator=(const FamilyEpisode&) = delete;

  const mjModel* model() const { return model_; }
  const std::vector<double>& torque_limits() const { return family_->hinge_torque_limit; }
  // The next episode's a (one value per range, inside it: EnvBatch::SetFamilyParameters checks).
  void SetNext(const float* a);
  // Starts an episode on `clip` at `frame`: a is the pending SetNext row or a uniform draw. With
  // body proportions in a, the episode's humanoid and clip are the scaled ones (body_model(),
  // scaled_clip()); a failure to build them leaves the unscaled ones and is returned.
  absl::Status Begin(const MotionClip& clip, int frame, std::mt19937_64& rng);
  // The episode's scaled humanoid and clip (kinematics and reference), or null at the session's
  // own proportions.
  const HumanoidModel* body_model() const { return body_model_.get(); }
  std::shared_ptr<const MotionClip> scaled_clip() const { return body_model_ ? scaled_clip_ : nullptr; }
  double phase() const { return phase_; }
  // Advances the phase by PhaseStep(tau), stopping at `last_frame`; returns the step taken.
  double Advance(float tau, int last_frame);
  // After the physics, against the reference at the new phase: the rewards, the obstacle touch
  // and the fitness frame.
  FamilyStepScore Score(const HumanoidState& sim, const HumanoidState& reference, const mjData* data,
                        double phase_step);
  // F of the episode's frames so far (0 before the first Score).
  double EpisodeFitness() const;
  const std::vector<float>& params() const { return a_; }
  // [a normalized to [0, 1] over each range (0 for a constraint) | phase / last_frame].
  void WriteGoal(int last_frame, float* goal) const;

 private:
  double Param(int index, double default_value) const { return index >= 0 ? a_[index] : default_value; }
  absl::Status ApplyToModel(const MotionClip& clip);
  absl::Status UseBodyProportions(const MotionClip& clip);
  void PlaceObstacle(const MotionClip& clip);
  float PeakSpike(double height, double vertical_velocity, double threshold, int param, double* prev_velocity,
                  bool* scored, double* constraint) const;
  void AddFitnessFrame(const HumanoidState& sim, const HumanoidState& reference);

  const FamilyContext* family_;
  const mjModel* base_;
  mjModel* model_;
  std::vector<float> a_, next_;
  bool has_next_ = false;
  double phase_ = 0;
  double prev_root_vz_ = 0, prev_effector_vz_ = 0;
  bool jump_scored_ = false, target_scored_ = false, touched_obstacle_ = false;
  double r_jump_ = 0, r_target_ = 0;
  FitnessAccumulator fitness_;
  std::vector<double> foot_speeds_;  // scratch: speeds of the feet in contact
  std::vector<Vec3> prev_foot_pos_;   // per foot, at the previous control step
  std::vector<char> prev_foot_contact_;
  std::shared_ptr<const HumanoidModel> body_model_;  // the episode's scaled humanoid, or null
  std::shared_ptr<MotionClip> scaled_clip_;          // the clip on it (buffers kept across episodes)
  double root_start_height_ = 0, effector_start_height_ = 0;  // the episode's clip's
  std::vector<double> foot_contact_height_;                   // per foot, the episode's clip's
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_FAMILY_EPISODE_H_
