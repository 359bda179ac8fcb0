#include "server/core/env/tracking_env.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "absl/strings/str_cat.h"
#include "common/log.h"
#include "server/core/env/base_motion_anchor.h"
#include "server/core/env/observation.h"

namespace modskill {

TrackingEnv::TrackingEnv(const EnvContext* context, uint64_t seed)
    : context_(context),
      goal_task_(MakeGoalTask(context->spec->task, &context->goal_task)),
      data_(mj_makeData(context->humanoid->model())), pd_(*context->humanoid), rng_(seed),
      kinematics_(context->humanoid.get()) {
  const int bodies = context->humanoid->num_bodies(), hinges = context->humanoid->num_hinges();
  sim_.Resize(bodies, hinges);
  reference_.Resize(bodies, hinges);
  target_.Resize(bodies, hinges);
  upcoming_.Resize(bodies, hinges);
  pd_targets_.assign(hinges, 0.0);
  body_distance_.assign(bodies, 0.0);
  amp_history_.assign(static_cast<size_t>(kAmpHistory) * context->spec->amp_obs_per_frame, 0.f);
  if (context->family != nullptr) {
    family_ = std::make_unique<FamilyEpisode>(context->family.get(), context->humanoid->model());
    pd_.UseModel(family_->model());
    pd_.UseTorqueLimits(&family_->torque_limits());
  }
}

TrackingEnv::~TrackingEnv() { mj_deleteData(data_); }

void TrackingEnv::Reset(EnvRow row) {
  const int clip = context_->sampler->Sample(rng_);
  const int frames = context_->motions->clip(clip).num_frames;
  // The last frame has no next target, so episodes start at most at frames - 2.
  // A family's episodes play the clip from its start, as the paper's do.
  const int frame = context_->config.random_start_frame && family_ == nullptr
                        ? std::uniform_int_distribution<int>(0, std::max(0, frames - 2))(rng_)
                        : 0;
  ResetTo(clip, frame, row);
}

void TrackingEnv::ResetTo(int clip, int frame, EnvRow row) {
  motion_ = context_->motions->shared_clip(clip);
  kinematics_ = context_->humanoid.get();
  clip_ = context_->clip_ids.empty() ? clip : context_->clip_ids[clip];
  frame_ = std::clamp(frame, 0, motion_->num_frames - 2);
  episode_steps_ = 0;
  loop_motion_ = PlanarMotion();
  reference_yaw_ = 0;
  if (LoopsClip()) cycle_motion_ = ClipCycleMotion(*motion_);
  finished_ = false;
  if (family_ != nullptr) {
    if (absl::Status status = family_->Begin(*motion_, frame_, rng_); !status.ok()) {
      LogLine("family episode at the session's own body proportions: %s", std::string(status.message()));
    }
    // At other body proportions the episode tracks the clip on its own skeleton.
    if (family_->body_model() != nullptr) {
      motion_ = family_->scaled_clip();
      kinematics_ = family_->body_model();
    }
  }
  const MotionClip& motion = *motion_;
  SetSimulationToReference(*kinematics_, motion, frame_, data_);
  if (goal_task_ != nullptr) {
    ReadSimulatedState(*kinematics_, data_, &sim_);
    goal_task_->Reset(sim_, data_, rng_);
    base_heading_ = HeadingAngle(sim_.body_rot[0]);
  }
  // AMP history starts as the reference's own recent past.
  context_->reference_amp->WriteHistory(clip, frame_, amp_history_.data());
  amp_head_ = 0;  // the newest frame sits at amp_head_, older ones at amp_head_ + 1, + 2, ...
  WriteObservation(row);
}

void TrackingEnv::RefreshObservation(EnvRow row) { WriteObservation(row); }

bool TrackingEnv::PhysicsDiverged() const {
  const mjModel* m = context_->humanoid->model();
  for (int i = 0; i < m->nq; ++i) {
    if (!std::isfinite(data_->qpos[i])) return true;
  }
  for (int i = 0; i < m->nv; ++i) {
    if (!std::isfinite(data_->qvel[i]) || std::abs(data_->qvel[i]) > 1e3) return true;
  }
  // MuJoCo resets the state itself on a NaN or huge qpos/qvel/qacc and only leaves a warning.
  return data_->warning[mjWARN_BADQACC].number > 0 || data_->warning[mjWARN_BADQVEL].number > 0 ||
         data_->warning[mjWARN_BADQPOS].number > 0;
}

TrackingErrors TrackingEnv::CurrentTrackingTerms(float* terms) {
  ReadSimulatedState(*kinematics_, data_, &sim_);
  ReadReferenceState(*motion_, frame_, &reference_);
  if (MovesReference()) loop_motion_.Apply(&reference_);
  return ComputeImitationTerms(context_->config.reward, sim_, reference_, terms, body_distance_.data());
}

int TrackingEnv::NextFrame() const {
  const int last = motion_->num_frames - 1;
  // A goal task's base motion loops. It goes on at frame 1: the step from frame 0 to 1 is one the
  // clip has, so the anchored reference (WriteObservation) moves as the clip does across the seam.
  if (goal_task_ != nullptr || LoopsClip()) return frame_ >= last ? std::min(1, last) : frame_ + 1;
  return std::min(frame_ + 1, last);
}

PlanarMotion TrackingEnv::LoopMotionOf(int frame) const {
  return frame < frame_ ? loop_motion_.After(cycle_motion_) : loop_motion_;
}

void TrackingEnv::Step(const float* action, EnvRow row) {
  if (finished_) {
    row.buffers->done[row.index] = 1;
    row.buffers->reward[row.index] = 0.f;
    return;
  }
  if (family_ != nullptr) {
    StepFamily(action, row);
    return;
  }
  const TrackingEnvConfig& config = context_->config;
  // Residual actions displace the reference pose of the frame this step reaches.
  const MotionClip& motion = *motion_;
  const int next_frame = NextFrame();
  MapActionToPdTargets(config.action, *context_->humanoid, *context_->spec, action,
                       &motion.dof_pos[static_cast<size_t>(next_frame) * motion.num_hinges()],
                       &motion.dof_vel[static_cast<size_t>(next_frame) * motion.num_hinges()], pd_targets_.data());
  const double power = pd_.Step(pd_targets_.data(), data_);
  ++episode_steps_;
  // An anchored reference keeps the motion WriteObservation found: it carried next_frame.
  if (LoopsClip() && !AnchorsReference()) loop_motion_ = LoopMotionOf(next_frame);
  if (LoopsClip() && next_frame < frame_) reference_yaw_ += HeadingAngle(cycle_motion_.yaw);
  // A tracking episode ends on reaching the last frame, so a step never starts there.
  frame_ = next_frame;
  if (PhysicsDiverged()) {
    EndOnBlowUp(row);
    return;
  }
  BatchBuffers& out = *row.buffers;
  float* terms = &out.reward_terms[static_cast<size_t>(row.index) * out.widths.reward_terms];
  if (goal_task_ != nullptr) {
    ScoreGoalTask(terms, row);
    if (SteersBaseMotion()) {
      const double max_turn = context_->goal_task.settings.steering_rate * M_PI / 180 * context_->spec->control_dt;
      base_heading_ = SteerHeading(base_heading_, sim_, goal_task_->GoalBearing(sim_, data_), max_turn);
    }
    AddEnergyAndSum(power, terms, row);
    const EpisodeEnd failure = goal_task_->Failed(data_) ? EpisodeEnd::kTask
                               : episode_steps_ > 1 && context_->fall_detector->Fallen(data_, sim_) ? EpisodeEnd::kFall
                                                                                                    : EpisodeEnd::kNone;
    FinishStep(failure, episode_steps_ >= TaskEpisodeSteps(config.max_episode_steps), row);
    return;
  }
  const TrackingErrors errors = ScoreTracking(terms, row);
  AddEnergyAndSum(power, terms, row);
  const bool at_end = LoopsClip() ? episode_steps_ >= TaskEpisodeSteps(config.max_episode_steps)
                                  : frame_ >= motion.num_frames - 1 ||
                                        (config.max_episode_steps > 0 && episode_steps_ >= config.max_episode_steps);
  FinishStep(Terminated(errors) ? EpisodeEnd::kTracking : EpisodeEnd::kNone, at_end, row);
}

void TrackingEnv::EndOnBlowUp(EnvRow row) {
  // A blow-up ends this episode only; the other envs never see it.
  ++physics_resets_;
  BatchBuffers& out = *row.buffers;
  const int i = row.index;
  float* terms = &out.reward_terms[static_cast<size_t>(i) * out.widths.reward_terms];
  std::fill(terms, terms + out.widths.reward_terms, 0.f);
  out.reward[i] = 0.f;
  out.done[i] = 1;
  out.truncated[i] = 0;
  out.end_cause[i] = static_cast<uint8_t>(EpisodeEnd::kBlowUp);
  out.ended_clip_id[i] = clip_;
  out.ended_frame[i] = frame_;
  out.max_body_error[i] = std::numeric_limits<float>::infinity();
  out.mean_body_error[i] = std::numeric_limits<float>::infinity();
  float* part_error = &out.part_error[static_cast<size_t>(i) * out.widths.parts];
  std::fill(part_error, part_error + out.widths.parts, std::numeric_limits<float>::infinity());
  EndEpisode(row);
}

TrackingErrors TrackingEnv::ScoreTracking(float* terms, EnvRow row) {
  TrackingErrors errors = CurrentTrackingTerms(terms);
  if (context_->spec->task == TaskKind::kVrTracking) errors = VrErrors();
  WriteErrors(errors, row);
  return errors;
}

void TrackingEnv::WriteErrors(const TrackingErrors& errors, EnvRow row) const {
  BatchBuffers& out = *row.buffers;
  out.max_body_error[row.index] = static_cast<float>(errors.max_body_distance);
  out.mean_body_error[row.index] = static_cast<float>(errors.mean_body_distance);
  WritePartErrors(&out.part_error[static_cast<size_t>(row.index) * out.widths.parts]);
}

TrackingErrors TrackingEnv::VrErrors() const {
  TrackingErrors errors;
  for (int b : context_->vr_body_ids) {
    errors.max_body_distance = std::max(errors.max_body_distance, body_distance_[b]);
    errors.mean_body_distance += body_distance_[b] / context_->vr_body_ids.size();
  }
  return errors;
}

void TrackingEnv::ScoreGoalTask(float* terms, EnvRow row) {
  BatchBuffers& out = *row.buffers;
  const int i = row.index;
  ReadSimulatedState(*kinematics_, data_, &sim_);
  goal_task_->Reward(sim_, data_, terms);
  // No reference to be far from: the errors say nothing in a goal task.
  out.max_body_error[i] = 0.f;
  out.mean_body_error[i] = 0.f;
  float* part_error = &out.part_error[static_cast<size_t>(i) * out.widths.parts];
  std::fill(part_error, part_error + out.widths.parts, 0.f);
}

void TrackingEnv::AddEnergyAndSum(double power, float* terms, EnvRow row) const {
  const ImitationRewardConfig& reward_config = context_->config.reward;
  const int64_t columns = row.buffers->widths.reward_terms;
  terms[columns - 1] =
      episode_steps_ > reward_config.energy_free_steps ? static_cast<float>(-reward_config.energy_coefficient * power) : 0.f;
  float reward = 0.f;
  for (int64_t t = 0; t < columns; ++t) reward += terms[t];
  row.buffers->reward[row.index] = reward;
}

void TrackingEnv::FinishStep(EpisodeEnd failure, bool at_end, EnvRow row) {
  BatchBuffers& out = *row.buffers;
  const int i = row.index;
  const bool terminated = failure != EpisodeEnd::kNone;
  const bool truncated = !terminated && at_end;
  out.done[i] = terminated || truncated;
  out.truncated[i] = truncated;
  out.end_cause[i] = static_cast<uint8_t>(terminated ? failure : truncated ? EpisodeEnd::kTime : EpisodeEnd::kNone);
  if (terminated || truncated) {
    out.ended_clip_id[i] = clip_;
    out.ended_frame[i] = frame_;
    EndEpisode(row);
    return;
  }
  if (goal_task_ != nullptr) goal_task_->NextGoal(sim_, rng_);
  // Push the new frame into the AMP ring.
  const EnvSpec& spec = *context_->spec;
  const int per_frame = spec.amp_obs_per_frame;
  amp_head_ = (amp_head_ + kAmpHistory - 1) % kAmpHistory;
  WriteAmpFrame(spec, sim_, &amp_history_[static_cast<size_t>(amp_head_) * per_frame]);
  WriteObservation(row);
}

bool TrackingEnv::Terminated(const TrackingErrors& errors) const {
  const TrackingEnvConfig& config = context_->config;
  switch (config.termination) {
    case TerminationMode::kTraining: {
      // Never on the first step after a reset (PHC): the state there is the reference's own.
      if (episode_steps_ <= 1) return false;
      double farthest = 0;
      for (int b : context_->termination_body_ids) farthest = std::max(farthest, body_distance_[b]);
      return farthest > config.termination_distance;
    }
    case TerminationMode::kEvaluation:
      return errors.mean_body_distance > config.termination_distance;
    case TerminationMode::kNone:
      return false;
  }
  return false;
}

void TrackingEnv::WritePartErrors(float* part_error) const {
  // body_distance_ holds this step's distances (CurrentTrackingTerms just computed them).
  const std::vector<BodyPart>& parts = context_->spec->layout.parts;
  for (size_t p = 0; p < parts.size(); ++p) {
    double total = 0;
    for (int b : parts[p].bodies) total += body_distance_[b];
    part_error[p] = parts[p].bodies.empty() ? 0.f : static_cast<float>(total / parts[p].bodies.size());
  }
}

void TrackingEnv::EndEpisode(EnvRow row) {
  if (context_->config.auto_reset) {
    Reset(row);
  } else {
    finished_ = true;
  }
}

void TrackingEnv::WriteObservation(EnvRow row) {
  const EnvSpec& spec = *context_->spec;
  const MotionClip& motion = *motion_;
  BatchBuffers& out = *row.buffers;
  const int i = row.index;
  float* obs = &out.obs[static_cast<size_t>(i) * spec.obs_size];
  ReadSimulatedState(*kinematics_, data_, &sim_);
  if (family_ != nullptr) {
    WriteFamilyObservation(obs, row);
  } else if (goal_task_ != nullptr) {
    // The base motion's next frame, carried onto the character from the frame before it (a loop
    // goes on at frame 1, so there always is one).
    const int next_frame = NextFrame();
    ReadReferenceState(motion, next_frame, &target_);
    ReadReferenceState(motion, next_frame - 1, &reference_);
    if (SteersBaseMotion()) {
      AnchorToHeading(reference_, sim_, base_heading_, &target_);
    } else {
      AnchorToCharacter(reference_, sim_, &target_);
    }
    WriteTrackingObservation(spec, sim_, target_, obs);
    goal_task_->WriteGoal(sim_, data_, obs + spec.goal_obs.start);
  } else {
    const int next_frame = NextFrame();
    ReadReferenceState(motion, next_frame, &target_);
    if (AnchorsReference()) {
      // As a goal task's base motion: the frame before the next one put on the character, the
      // next frame moved with it; Step scores against the same motion.
      ReadReferenceState(motion, next_frame - 1, &reference_);
      if (context_->config.anchor_position_only) {
        // The clip's heading as global tracking would have it; a wrap starts the next cycle.
        const double cycle = LoopsClip() && next_frame < frame_ ? HeadingAngle(cycle_motion_.yaw) : 0.0;
        const double heading = HeadingAngle(reference_.body_rot[0]) + reference_yaw_ + cycle;
        loop_motion_ = AnchorToHeading(reference_, sim_, heading, &target_);
      } else {
        loop_motion_ = AnchorToCharacter(reference_, sim_, &target_);
      }
    } else if (LoopsClip()) {
      LoopMotionOf(next_frame).Apply(&target_);
    }
    if (spec.task == TaskKind::kVrTracking) {
      WriteSelfObservation(spec, sim_, obs);
      for (size_t k = 0; k < context_->vr_body_ids.size(); ++k) {
        WriteBodyTaskFeatures(sim_, target_, context_->vr_body_ids[k],
                              obs + spec.goal_obs.start + k * kTaskFeaturesPerBody);
      }
    } else {
      WriteTrackingObservation(spec, sim_, target_, obs);
      for (int k = 1; k < spec.reference_frames; ++k) {
        ReadReferenceState(motion, std::min(next_frame + k, motion.num_frames - 1), &upcoming_);
        WriteUpcomingReferenceObservation(spec, sim_, upcoming_, k, obs);
      }
    }
  }
  // AMP rows are newest first.
  float* amp = &out.amp_obs[static_cast<size_t>(i) * spec.amp_obs_size];
  const int per_frame = spec.amp_obs_per_frame;
  for (int k = 0; k < kAmpHistory; ++k) {
    const int slot = (amp_head_ + k) % kAmpHistory;
    std::memcpy(amp + static_cast<size_t>(k) * per_frame, &amp_history_[static_cast<size_t>(slot) * per_frame],
                sizeof(float) * per_frame);
  }
  out.clip_id[i] = clip_;
  out.frame[i] = frame_;
}

}  // namespace modskill
