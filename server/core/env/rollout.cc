#include "server/core/env/rollout.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "server/core/env/task_catalog.h"

namespace modskill {
namespace {

// Body positions of one clip's rollout, frame by frame, for the sim and the reference.
struct Trajectory {
  std::vector<std::vector<Vec3>> sim;
  std::vector<std::vector<Vec3>> ref;
  double worst_mean_error = 0;
};

ClipRolloutMetrics Measure(const Trajectory& t, const std::string& name, bool success, const PartLayout& layout) {
  ClipRolloutMetrics m;
  m.clip = name;
  m.success = success;
  m.steps = static_cast<int>(t.sim.size()) - 1;
  m.worst_mean_body_error = t.worst_mean_error;
  const int frames = static_cast<int>(t.sim.size());
  const int bodies = frames > 0 ? static_cast<int>(t.sim[0].size()) : 0;
  m.body_error_mm.assign(bodies, 0.0);
  if (frames == 0 || bodies == 0) return m;
  for (int f = 0; f < frames; ++f) {
    for (int b = 0; b < bodies; ++b) {
      const double global = (t.sim[f][b] - t.ref[f][b]).norm();
      const double local = ((t.sim[f][b] - t.sim[f][0]) - (t.ref[f][b] - t.ref[f][0])).norm();
      m.body_error_mm[b] += 1000.0 * global / frames;
      m.g_mpjpe_mm += 1000.0 * global / (frames * bodies);
      m.mpjpe_mm += 1000.0 * local / (frames * bodies);
    }
  }
  // Per-frame finite differences, as PHC computes E_vel and E_acc.
  if (frames >= 2) {
    for (int f = 0; f + 1 < frames; ++f) {
      for (int b = 0; b < bodies; ++b) {
        const Vec3 v_sim = t.sim[f + 1][b] - t.sim[f][b], v_ref = t.ref[f + 1][b] - t.ref[f][b];
        m.vel_error_mm += 1000.0 * (v_sim - v_ref).norm() / ((frames - 1) * bodies);
      }
    }
  }
  if (frames >= 3) {
    for (int f = 1; f + 1 < frames; ++f) {
      for (int b = 0; b < bodies; ++b) {
        const Vec3 a_sim = t.sim[f + 1][b] - 2 * t.sim[f][b] + t.sim[f - 1][b];
        const Vec3 a_ref = t.ref[f + 1][b] - 2 * t.ref[f][b] + t.ref[f - 1][b];
        m.acc_error_mm += 1000.0 * (a_sim - a_ref).norm() / ((frames - 2) * bodies);
      }
    }
  }
  for (const BodyPart& part : layout.parts) {
    double sum = 0;
    for (int b : part.bodies) sum += m.body_error_mm[b];
    m.part_error_mm.push_back(sum / part.bodies.size());
  }
  return m;
}

// The bodies whose mean distance evaluation termination watches: the task's tracked bodies
// (vr_tracking's head and hands), or every body.
std::vector<int> WatchedBodies(const HumanoidModel& humanoid, TaskKind task) {
  std::vector<int> bodies = TrackedBodyIndices(task, humanoid.spec());
  if (bodies.empty()) {
    for (int b = 0; b < humanoid.num_bodies(); ++b) bodies.push_back(b);
  }
  return bodies;
}

// How many steps a rollout of `clip` could last: the step limit, or the clip's length in tracking.
double PossibleSteps(const RolloutOptions& options, const MotionClip& clip) {
  const bool goal_task = IsGoalTask(options.task);
  if (goal_task) return TaskEpisodeSteps(options.max_steps_per_clip);
  int steps = clip.num_frames - 1;
  if (options.max_steps_per_clip > 0) steps = std::min(steps, options.max_steps_per_clip);
  return std::max(1, steps);
}

// Creates the rollout's envs, one per clip, reset to each clip's first frame.
absl::StatusOr<std::unique_ptr<EnvBatch>> RolloutBatch(std::shared_ptr<const HumanoidModel> humanoid,
                                                       const PartLayout& layout,
                                                       std::shared_ptr<const MotionLibrary> motions,
                                                       const std::vector<int>& clip_ids,
                                                       const RolloutOptions& options) {
  if (clip_ids.empty()) return absl::InvalidArgumentError("clips: none to roll out");
  for (int id : clip_ids) {
    if (id < 0 || id >= motions->size()) return absl::NotFoundError(absl::StrCat("clips: no clip with index ", id));
  }
  EnvBatchConfig config;
  config.num_envs = static_cast<int>(clip_ids.size());
  config.num_threads = std::max(1, options.num_threads);
  config.env.termination = options.termination;
  config.env.termination_distance = options.termination_distance;
  config.env.action = options.action;
  config.env.reference_frames = options.reference_frames;
  config.env.max_episode_steps = options.max_steps_per_clip;
  config.env.auto_reset = false;
  config.env.task = options.task;
  config.env.task_settings = options.task_settings;
  config.seed = options.seed;
  config.physics = options.physics;
  config.env.family = options.family;
  auto created = EnvBatch::Create(config, humanoid, layout, motions);
  if (!created.ok()) return created.status();
  if (!options.family.empty()) {
    // Every env's first episode runs at a (the pending parameters the reset below begins with).
    std::vector<float> rows;
    for (size_t i = 0; i < clip_ids.size(); ++i) rows.insert(rows.end(), options.family_params.begin(), options.family_params.end());
    if (absl::Status status = (*created)->SetFamilyParameters(rows); !status.ok()) return status;
  }
  for (int i = 0; i < (*created)->num_envs(); ++i) (*created)->env(i).ResetTo(clip_ids[i], 0, (*created)->row(i));
  return created;
}

// A family episode's measures: how the body moved, its fitness, how far along the clip it got.
void AddFamilyMeasures(const FamilyMotionMeter& meter, double fitness, const TrackingEnv& env, const MotionClip& clip,
                       ClipRolloutMetrics* m) {
  m->has_family = true;
  m->family = meter.measures();
  m->fitness = fitness;
  m->final_phase = env.family()->phase();
  m->reached_end = m->final_phase >= clip.num_frames - 1;
}

}  // namespace

absl::StatusOr<std::vector<ClipRolloutMetrics>> RunRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                           const PartLayout& layout,
                                                           std::shared_ptr<const MotionLibrary> motions,
                                                           const std::vector<int>& clip_ids,
                                                           const PolicyFunction& policy, const RolloutOptions& options,
                                                           const RolloutFrameCallback& on_frame,
                                                           const FrameSkills& frame_skills) {
  auto created = RolloutBatch(humanoid, layout, motions, clip_ids, options);
  if (!created.ok()) return created.status();
  EnvBatch& batch = **created;
  const int n = batch.num_envs();
  std::vector<Trajectory> trajectories(n);
  std::vector<bool> terminated(n, false);
  const bool family = !options.family.empty();
  std::vector<FamilyMotionMeter> meters(family ? n : 0, FamilyMotionMeter(humanoid->spec(), batch.spec().control_dt));
  std::vector<double> fitness(n, 0.0);
  const std::vector<int> watched = WatchedBodies(*humanoid, options.task);
  HumanoidState sim, ref;
  sim.Resize(humanoid->num_bodies(), humanoid->num_hinges());
  ref.Resize(humanoid->num_bodies(), humanoid->num_hinges());
  // Measures env i's current frame and shows it with the z the policy acted on from it.
  auto record = [&](int i, bool is_done, bool is_terminated, const float* z) {
    // A family's reference is the clip at its warped phase, on the episode's own skeleton.
    const FamilyEpisode* episode = batch.env(i).family();
    const MotionClip& clip = batch.env(i).motion();
    const HumanoidModel& kinematics = episode != nullptr && episode->body_model() ? *episode->body_model() : *humanoid;
    ReadSimulatedState(kinematics, batch.env(i).data(), &sim);
    if (episode != nullptr) {
      ReadReferenceStateAt(clip, episode->phase(), &ref);
      meters[i].Observe(sim);
    } else {
      ReadReferenceState(clip, batch.env(i).frame(), &ref);
    }
    trajectories[i].sim.push_back(sim.body_pos);
    trajectories[i].ref.push_back(ref.body_pos);
    double mean = 0;
    for (int b : watched) mean += (sim.body_pos[b] - ref.body_pos[b]).norm() / watched.size();
    trajectories[i].worst_mean_error = std::max(trajectories[i].worst_mean_error, mean);
    if (on_frame) on_frame({i, batch.env(i).frame(), sim, ref, mean, is_done, is_terminated, z});
  };

  std::vector<float> actions(static_cast<size_t>(n) * batch.spec().action_size);
  std::vector<bool> finished(n, false);
  std::vector<double> task_return(n, 0.0);
  const int64_t terms = batch.buffers().widths.reward_terms;
  int remaining = n;
  while (remaining > 0) {
    if (auto status = policy(batch.buffers().obs.data(), n, actions.data()); !status.ok()) return status;
    // The frames the policy just acted on (the state has not moved since the last step).
    for (int i = 0; i < n; ++i) {
      if (!finished[i]) record(i, false, false, frame_skills.z ? frame_skills.z + i * frame_skills.z_size : nullptr);
    }
    if (auto status = batch.Step(actions); !status.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("policy output: ", status.message()));
    }
    for (int i = 0; i < n; ++i) {
      if (finished[i]) continue;
      // Every column but the last, energy.
      for (int64_t t = 0; t + 1 < terms; ++t) task_return[i] += batch.buffers().reward_terms[i * terms + t];
      if (!batch.buffers().done[i]) continue;
      terminated[i] = !batch.buffers().truncated[i];
      fitness[i] = family ? batch.buffers().fitness[i] : 0.0;
      record(i, true, terminated[i], nullptr);
      finished[i] = true;
      --remaining;
    }
  }
  std::vector<ClipRolloutMetrics> metrics;
  for (int i = 0; i < n; ++i) {
    metrics.push_back(Measure(trajectories[i], motions->clip(clip_ids[i]).name, !terminated[i], layout));
    metrics.back().normalized_return = task_return[i] / PossibleSteps(options, motions->clip(clip_ids[i]));
    if (family) AddFamilyMeasures(meters[i], fitness[i], batch.env(i), motions->clip(clip_ids[i]), &metrics.back());
  }
  return metrics;
}

}  // namespace modskill
