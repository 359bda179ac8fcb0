// TrackingEnv in a motor-skill family session (family_episode.h): displacement mapping and time
// warping as the action, the reference read at the warped phase.
#include <algorithm>
#include <cmath>

#include "common/policy/task_episode.h"
#include "server/core/env/observation.h"
#include "server/core/env/tracking_env.h"

namespace modskill {
namespace {

// The family's own columns, after tracking's four terms: time, task, then energy (last).
constexpr int kTimeColumn = kRewardEnergy, kTaskColumn = kRewardEnergy + 1;

}  // namespace

void TrackingEnv::StepFamily(const float* action, EnvRow row) {
  const TrackingEnvConfig& config = context_->config;
  const EnvSpec& spec = *context_->spec;
  const MotionClip& motion = *motion_;
  const int last = motion.num_frames - 1;
  BatchBuffers& out = *row.buffers;
  const int i = row.index;
  // The time warp picks the phase this step reaches; the displacement moves its reference pose.
  const double phase_step = family_->Advance(action[spec.time_warp_action], last);
  ReadReferenceStateAt(motion, family_->phase(), &reference_);
  MapActionToPdTargets(config.action, *context_->humanoid, spec, action, reference_.dof_pos.data(), nullptr,
                       pd_targets_.data());
  const double power = pd_.Step(pd_targets_.data(), data_);
  ++episode_steps_;
  frame_ = static_cast<int>(std::floor(family_->phase()));
  out.phase_step[i] = static_cast<float>(phase_step);
  const std::vector<float>& params = family_->params();
  std::copy(params.begin(), params.end(), &out.ended_family_params[static_cast<size_t>(i) * params.size()]);
  if (PhysicsDiverged()) {
    out.spike_reward[i] = 0.f;
    out.fitness[i] = 0.f;
    EndOnBlowUp(row);
    return;
  }
  float* terms = &out.reward_terms[static_cast<size_t>(i) * out.widths.reward_terms];
  ReadSimulatedState(*kinematics_, data_, &sim_);
  const TrackingErrors errors =
      ComputeImitationTerms(config.reward, sim_, reference_, terms, body_distance_.data());
  WriteErrors(errors, row);
  const FamilyStepScore score = family_->Score(sim_, reference_, data_, phase_step);
  terms[kTimeColumn] = score.time_reward;
  terms[kTaskColumn] = score.spike;
  AddEnergyAndSum(power, terms, row);
  out.spike_reward[i] = score.spike;
  // A family leaves its clip by design: it fails by falling or drifting past the (loose) distance.
  const EpisodeEnd failure = episode_steps_ <= 1                                ? EpisodeEnd::kNone
                             : Terminated(errors)                                 ? EpisodeEnd::kTracking
                             : context_->fall_detector->Fallen(data_, sim_) ? EpisodeEnd::kFall
                                                                                  : EpisodeEnd::kNone;
  const bool failed = failure != EpisodeEnd::kNone;
  const bool at_end = family_->phase() >= last || episode_steps_ >= TaskEpisodeSteps(config.max_episode_steps);
  out.fitness[i] = failed || at_end ? static_cast<float>(family_->EpisodeFitness()) : 0.f;
  FinishStep(failure, at_end, row);
}

void TrackingEnv::WriteFamilyObservation(float* obs, EnvRow row) {
  const EnvSpec& spec = *context_->spec;
  const MotionClip& motion = *motion_;
  const int last = motion.num_frames - 1;
  // The reference one frame ahead at the clip's own pace, as the paper observes the next phase.
  ReadReferenceStateAt(motion, std::min(family_->phase() + 1.0, static_cast<double>(last)), &target_);
  WriteTrackingObservation(spec, sim_, target_, obs);
  family_->WriteGoal(last, obs + spec.goal_obs.start);
  const std::vector<float>& params = family_->params();
  std::copy(params.begin(), params.end(), &row.buffers->family_params[static_cast<size_t>(row.index) * params.size()]);
}

}  // namespace modskill
