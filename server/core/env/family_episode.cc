#include "server/core/env/family_episode.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "common/servo_settings.h"
#include "server/core/sim/mjcf_builder.h"
#include "server/core/sim/rotation_math.h"

namespace modskill {
namespace {

constexpr const char* kEffectorBodies[] = {"R_Ankle", "L_Ankle", "R_Wrist", "L_Wrist"};
constexpr double kObstacleHalfDepth = 0.05, kObstacleHalfWidth = 1.0;  // m
constexpr double kDefaultObstacleHeight = 0.1;                         // m

int IndexOf(const std::vector<ParamRange>& ranges, absl::string_view name) {
  for (size_t i = 0; i < ranges.size(); ++i) {
    if (ranges[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

// The clip's own heights and travel: the defaults of the height parameters and the levels a
// peak must clear.
void MeasureClip(const MotionClip& clip, FamilyContext* family) {
  const int bodies = clip.num_bodies;
  family->root_start_height = clip.body_pos[0].z();
  family->root_apex_height = family->root_start_height;
  family->effector_start_height = 0;
  for (int e : family->effectors) family->effector_start_height = std::max(family->effector_start_height, clip.body_pos[e].z());
  family->effector_peak_height = family->effector_start_height;
  for (int f = 0; f < clip.num_frames; ++f) {
    family->root_apex_height = std::max(family->root_apex_height, clip.body_pos[static_cast<size_t>(f) * bodies].z());
    for (int e : family->effectors) {
      family->effector_peak_height =
          std::max(family->effector_peak_height, clip.body_pos[static_cast<size_t>(f) * bodies + e].z());
    }
  }
  const Vec3 travel = clip.body_pos[static_cast<size_t>(clip.num_frames - 1) * bodies] - clip.body_pos[0];
  family->travel = std::hypot(travel.x(), travel.y());
  for (int foot : family->feet) family->foot_contact_height.push_back(clip.body_pos[foot].z() + 0.03);
}

// Lee et al. 2021, Table 3: the torque limit (N*m) of each joint group of their 61.7 kg character,
// scaled here by our character's mass over theirs so that strength per kilogram is theirs. It bounds
// each of a joint's three hinges (their limit bounds the norm of the joint's torque vector).
constexpr double kPaperCharacterMass = 61.7;  // kg
double PaperTorqueLimit(absl::string_view body) {
  auto has = [&](absl::string_view s) { return absl::StrContains(body, s); };
  if (has("Hip") || has("Torso")) return 200;
  if (has("Knee")) return 150;
  if (has("Ankle")) return 90;
  if (has("Neck") || has("Head")) return 50;
  if (has("Elbow") || has("Wrist") || has("Hand") || has("Toe")) return 60;
  return 100;  // Spine, Chest, Thorax, Shoulder
}

}  // namespace

std::vector<double> FamilyTorqueLimits(const HumanoidSpec& spec, double character_mass) {
  std::vector<double> limits;
  for (int b = 1; b < spec.num_bodies(); ++b) {
    const double limit = PaperTorqueLimit(spec.body(b).name) * character_mass / kPaperCharacterMass;
    limits.insert(limits.end(), 3, limit);
  }
  return limits;
}

absl::Status ValidateFamilyRanges(absl::Span<const ParamRange> ranges, absl::string_view field) {
  if (ranges.empty()) return absl::InvalidArgumentError(absl::StrCat(field, ": no parameter ranges"));
  std::set<std::string> seen;
  for (const ParamRange& range : ranges) {
    if (absl::Status valid = ValidateParamRange(range); !valid.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(field, ": ", valid.message()));
    }
    if (!seen.insert(range.name).second) {
      return absl::InvalidArgumentError(absl::StrCat(field, ": param ", range.name, " is given twice"));
    }
  }
  return absl::OkStatus();
}

std::vector<FamilyParameterInfo> OfferedFamilyParameters() {
  std::vector<FamilyParameterInfo> offered;
  for (const FamilyParameterInfo& info : FamilyParameterCatalog()) offered.push_back(info);
  return offered;
}

bool FamilyNeedsObstacle(absl::Span<const ParamRange> ranges) {
  return std::any_of(ranges.begin(), ranges.end(), [](const ParamRange& range) {
    return range.name == "obstacle_height" || range.name == "obstacle_distance";
  });
}

absl::Status ValidateFamilySession(absl::Span<const ParamRange> ranges, absl::string_view ranges_field, int clips,
                                   TaskKind task, ActionMode action_mode, bool loop_clips) {
  if (absl::Status status = ValidateFamilyRanges(ranges, ranges_field); !status.ok()) return status;
  if (clips != 1) return absl::InvalidArgumentError(absl::StrCat("family: needs exactly one clip in motions, got ", clips));
  if (task != TaskKind::kTracking) return absl::InvalidArgumentError("family: a family session's task is tracking");
  if (action_mode != ActionMode::kResidual) {
    return absl::InvalidArgumentError("family: action_mode must be RESIDUAL (a displacement of the reference)");
  }
  if (loop_clips) return absl::InvalidArgumentError("family: loop_clips is not for a family session");
  return absl::OkStatus();
}

absl::StatusOr<std::shared_ptr<const FamilyContext>> MakeFamilyContext(std::vector<ParamRange> ranges,
                                                                       std::shared_ptr<const HumanoidModel> shared,
                                                                       const MotionClip& clip) {
  const HumanoidModel& humanoid = *shared;
  // The paper's torque limits bound the whole PD torque only under stable PD (env_batch.cc's
  // ModelForTask builds a family's model so).
  if (humanoid.options().pd_mode != PdMode::kStablePd) {
    return absl::InternalError("family: the session's model must use stable PD (pd_mode stable_pd)");
  }
  auto family = std::make_shared<FamilyContext>();
  family->gravity = IndexOf(ranges, "gravity");
  family->body_mass_scale = IndexOf(ranges, "body_mass_scale");
  family->jump_height = IndexOf(ranges, "jump_height");
  family->target_height = IndexOf(ranges, "target_height");
  family->obstacle_height = IndexOf(ranges, "obstacle_height");
  family->obstacle_distance = IndexOf(ranges, "obstacle_distance");
  family->leg_scale = IndexOf(ranges, "leg_scale");
  family->arm_scale = IndexOf(ranges, "arm_scale");
  if (family->leg_scale >= 0 || family->arm_scale >= 0) {
    family->body_models = std::make_shared<FamilyBodyModels>(shared);
    // The largest bodies of the ranges, built now: a model that cannot be copied into an env's
    // fails the session here, not an episode later.
    const double leg = family->leg_scale >= 0 ? ranges[family->leg_scale].hi : 1.0;
    const double arm = family->arm_scale >= 0 ? ranges[family->arm_scale].hi : 1.0;
    if (auto model = family->body_models->Get(leg, arm); !model.ok()) return model.status();
  }
  const mjModel* model = humanoid.model();
  if (FamilyNeedsObstacle(ranges)) {
    family->obstacle_geom = mj_name2id(model, mjOBJ_GEOM, kFamilyObstacleName);
    if (family->obstacle_geom < 0) return absl::InternalError("family: the model has no obstacle geom");
  }
  family->humanoid_geom.assign(model->ngeom, 0);
  for (int g = 0; g < model->ngeom; ++g) family->humanoid_geom[g] = model->geom_bodyid[g] != 0;
  const HumanoidSpec& spec = humanoid.spec();
  family->feet = FootBodies(spec);
  // A family model holds the humanoid and static geoms only (the obstacle is the world's).
  family->hinge_torque_limit = FamilyTorqueLimits(spec, mj_getTotalmass(model));
  family->control_dt = model->opt.timestep * humanoid.options().substeps;
  if (static_cast<int>(family->hinge_torque_limit.size()) != humanoid.num_hinges()) {
    return absl::InternalError("family: torque limits do not match the hinges");
  }
  for (const char* name : kEffectorBodies) family->effectors.push_back(spec.BodyIndex(name));
  family->ranges = std::move(ranges);
  MeasureClip(clip, family.get());
  return family;
}

void AddFamilyToSpec(const std::vector<ParamRange>& ranges, EnvSpec* spec) {
  const int goal = static_cast<int>(ranges.size()) + 1;
  spec->goal_obs = Slice{spec->obs_size, goal};
  spec->obs_size += goal;
  spec->task_obs_size += goal;
  spec->time_warp_action = spec->action_size;
  spec->action_size += 1;
  spec->reward_terms = {"pos", "rot", "vel", "ang_vel", "time", "task", "energy"};
  spec->family = ranges;
  // A family session simulates with stable PD (env_batch.cc's ModelForTask) and tracks a warped
  // clip that has no rate to damp toward, whatever the server's flags.
  spec->physics.pd_mode = std::string(kPdModeStablePd);
  spec->physics.damp_to_reference_rate = false;
}

double PhaseStep(float tau) { return std::exp(std::clamp(1.5 * static_cast<double>(tau), -2.0, 1.0)); }

FamilyEpisode::FamilyEpisode(const FamilyContext* family, const mjModel* base)
    : family_(family), base_(base), model_(mj_copyModel(nullptr, base)) {
  if (family->body_models != nullptr) scaled_clip_ = std::make_shared<MotionClip>();
  root_start_height_ = family->root_start_height;
  effector_start_height_ = family->effector_start_height;
  foot_contact_height_ = family->foot_contact_height;
  a_.assign(family->ranges.size(), 0.f);
  next_.assign(family->ranges.size(), 0.f);
  foot_speeds_.reserve(family->feet.size());
  prev_foot_pos_.assign(family->feet.size(), Vec3::Zero());
  prev_foot_contact_.assign(family->feet.size(), 0);
}

FamilyEpisode::~FamilyEpisode() { mj_deleteModel(model_); }

void FamilyEpisode::SetNext(const float* a) {
  std::copy_n(a, next_.size(), next_.begin());
  has_next_ = true;
}

absl::Status FamilyEpisode::Begin(const MotionClip& clip, int frame, std::mt19937_64& rng) {
  if (has_next_) {
    a_ = next_;
  } else {
    for (size_t i = 0; i < a_.size(); ++i) {
      const ParamRange& range = family_->ranges[i];
      a_[i] = static_cast<float>(std::uniform_real_distribution<double>(range.lo, range.hi)(rng));
    }
  }
  const absl::Status applied = ApplyToModel(clip);
  phase_ = frame;
  prev_root_vz_ = prev_effector_vz_ = 0;
  std::fill(prev_foot_contact_.begin(), prev_foot_contact_.end(), 0);
  jump_scored_ = target_scored_ = touched_obstacle_ = false;
  r_jump_ = r_target_ = 0;
  fitness_ = FitnessAccumulator();
  return applied;
}

absl::Status FamilyEpisode::UseBodyProportions(const MotionClip& clip) {
  const double leg = Param(family_->leg_scale, 1.0), arm = Param(family_->arm_scale, 1.0);
  auto model = family_->body_models->Get(leg, arm);
  if (!model.ok()) return model.status();
  // Same layout (FamilyBodyModels checks): the numbers are copied into this env's buffer.
  mj_copyModel(model_, (*model)->model());
  if (absl::Status status = ScaleClip(clip, (*model)->spec(), leg, scaled_clip_.get()); !status.ok()) return status;
  body_model_ = *std::move(model);
  // The heights a peak must clear are the scaled clip's.
  root_start_height_ = scaled_clip_->body_pos[0].z();
  effector_start_height_ = 0;
  for (int e : family_->effectors) effector_start_height_ = std::max(effector_start_height_, scaled_clip_->body_pos[e].z());
  for (size_t f = 0; f < family_->feet.size(); ++f) {
    foot_contact_height_[f] = scaled_clip_->body_pos[family_->feet[f]].z() + 0.03;
  }
  return absl::OkStatus();
}

absl::Status FamilyEpisode::ApplyToModel(const MotionClip& clip) {
  absl::Status proportions;
  const mjModel* shape = base_;  // the masses a body_mass_scale multiplies
  if (family_->body_models != nullptr) {
    proportions = UseBodyProportions(clip);
    if (proportions.ok()) {
      shape = body_model_->model();
    } else {
      // The session's own body then: its numbers back in this env's copy.
      body_model_ = nullptr;
      mj_copyModel(model_, base_);
      root_start_height_ = family_->root_start_height;
      effector_start_height_ = family_->effector_start_height;
      foot_contact_height_ = family_->foot_contact_height;
    }
  }
  model_->opt.gravity[2] = -Param(family_->gravity, -base_->opt.gravity[2]);
  const double mass_scale = Param(family_->body_mass_scale, 1.0);
  for (int b = 0; b < shape->nbody; ++b) {
    model_->body_mass[b] = shape->body_mass[b] * mass_scale;
    model_->body_subtreemass[b] = shape->body_subtreemass[b] * mass_scale;
    for (int k = 0; k < 3; ++k) model_->body_inertia[3 * b + k] = shape->body_inertia[3 * b + k] * mass_scale;
  }
  if (family_->obstacle_geom >= 0) PlaceObstacle(body_model_ ? *scaled_clip_ : clip);
  return proportions;
}

void FamilyEpisode::PlaceObstacle(const MotionClip& clip) {
  const double height = std::max(Param(family_->obstacle_height, kDefaultObstacleHeight), 0.002);
  const double distance = Param(family_->obstacle_distance, 0.5 * family_->travel);
  // Across the clip's start heading, `distance` ahead of the start root, standing on the floor.
  const Quat heading = HeadingRotation(clip.body_rot[0]);
  const Vec3 ahead = heading * Vec3::UnitX();
  const int g = family_->obstacle_geom;
  model_->geom_pos[3 * g + 0] = clip.body_pos[0].x() + distance * ahead.x();
  model_->geom_pos[3 * g + 1] = clip.body_pos[0].y() + distance * ahead.y();
  model_->geom_pos[3 * g + 2] = 0.5 * height;
  model_->geom_quat[4 * g + 0] = heading.w();
  model_->geom_quat[4 * g + 1] = heading.x();
  model_->geom_quat[4 * g + 2] = heading.y();
  model_->geom_quat[4 * g + 3] = heading.z();
  model_->geom_size[3 * g + 0] = kObstacleHalfDepth;
  model_->geom_size[3 * g + 1] = kObstacleHalfWidth;
  model_->geom_size[3 * g + 2] = 0.5 * height;
  // The broad phase culls by the bounding sphere.
  model_->geom_rbound[g] = std::sqrt(kObstacleHalfDepth * kObstacleHalfDepth +
                                     kObstacleHalfWidth * kObstacleHalfWidth + 0.25 * height * height);
}

double FamilyEpisode::Advance(float tau, int last_frame) {
  const double before = phase_;
  phase_ = std::min(phase_ + PhaseStep(tau), static_cast<double>(last_frame));
  return phase_ - before;
}

float FamilyEpisode::PeakSpike(double height, double vertical_velocity, double threshold, int param,
                               double* prev_velocity, bool* scored, double* constraint) const {
  const bool peak = *prev_velocity > 0 && vertical_velocity <= 0 && height > threshold;
  *prev_velocity = vertical_velocity;
  if (param < 0 || *scored || !peak) return 0.f;
  *scored = true;
  const double error = (height - a_[param]) / kFamilyPeakSigma;
  *constraint = std::exp(-error * error);
  return static_cast<float>(kFamilySpikeWeight * *constraint);
}

FamilyStepScore FamilyEpisode::Score(const HumanoidState& sim, const HumanoidState& reference, const mjData* data,
                                     double phase_step) {
  FamilyStepScore score;
  const double time_error = phase_step - 1.0;
  score.time_reward = static_cast<float>(kFamilyTimeWeight * std::exp(-time_error * time_error / kFamilyTimeSigma));
  score.spike += PeakSpike(sim.body_pos[0].z(), sim.body_vel[0].z(), root_start_height_ + 0.05,
                           family_->jump_height, &prev_root_vz_, &jump_scored_, &r_jump_);
  int highest = family_->effectors[0];
  for (int e : family_->effectors) {
    if (sim.body_pos[e].z() > sim.body_pos[highest].z()) highest = e;
  }
  score.spike += PeakSpike(sim.body_pos[highest].z(), sim.body_vel[highest].z(), effector_start_height_ + 0.2,
                           family_->target_height, &prev_effector_vz_, &target_scored_, &r_target_);
  for (int c = 0; c < data->ncon && family_->obstacle_geom >= 0; ++c) {
    const mjContact& contact = data->contact[c];
    const int other = contact.geom1 == family_->obstacle_geom   ? contact.geom2
                      : contact.geom2 == family_->obstacle_geom ? contact.geom1
                                                                : -1;
    if (other >= 0 && family_->humanoid_geom[other]) touched_obstacle_ = true;
  }
  AddFitnessFrame(sim, reference);
  return score;
}

void FamilyEpisode::AddFitnessFrame(const HumanoidState& sim, const HumanoidState& reference) {
  FitnessFrame frame;
  const size_t hinges = sim.dof_pos.size();
  for (size_t h = 0; h < hinges; ++h) {
    const double dq = sim.dof_pos[h] - reference.dof_pos[h], dw = sim.dof_vel[h] - reference.dof_vel[h];
    frame.pose_error += dq * dq;
    frame.velocity_error += dw * dw;
  }
  // Means over the hinges, as the authors' code normalizes them: summed over our 69 hinges, a
  // walk-quality motion scored F ~ 0.01 and no episode could ever pass an acceptance of 0.5.
  const double hinge_count = static_cast<double>(std::max<size_t>(hinges, 1));
  frame.pose_error /= hinge_count;
  frame.velocity_error /= hinge_count;
  foot_speeds_.clear();
  for (size_t f = 0; f < family_->feet.size(); ++f) {
    const int body = family_->feet[f];
    const bool sim_contact = sim.body_pos[body].z() < foot_contact_height_[f];
    const bool reference_contact = reference.body_pos[body].z() < foot_contact_height_[f];
    // Graded, as in the authors' code: how far the foot is from where the reference has it (in
    // height, x5), counted where either foot is on the floor. A binary mismatch count punished
    // a foot 1 mm over the contact height like one in the air (F 0.35 for the clip's own motion).
    if (sim_contact || reference_contact) {
      const double dz = 5.0 * (sim.body_pos[body].z() - reference.body_pos[body].z());
      frame.contact_error += dz * dz;
    }
    // Drag: how fast a foot on the floor at both ends of the control step moved over it (the
    // authors' code measures the same displacement); the instantaneous speed of a planted foot
    // jitters above V under a little action noise and put f_drag at 0.4 for a jump that held.
    const Vec3& p = sim.body_pos[body];
    if (sim_contact && prev_foot_contact_[f]) {
      foot_speeds_.push_back(std::hypot(p.x() - prev_foot_pos_[f].x(), p.y() - prev_foot_pos_[f].y()) /
                             family_->control_dt);
    }
    prev_foot_pos_[f] = p;
    prev_foot_contact_[f] = sim_contact;
  }
  frame.contact_foot_speeds = foot_speeds_;
  // A blow-up ends the episode before this; a measure is never negative, so this cannot fail.
  fitness_.AddFrame(frame).IgnoreError();
}

double FamilyEpisode::EpisodeFitness() const {
  double constraint = 0;
  bool any = false;
  auto combine = [&](bool active, double r) {
    if (!active) return;
    constraint = any ? constraint * r : r;
    any = true;
  };
  combine(family_->jump_height >= 0, r_jump_);
  combine(family_->target_height >= 0, r_target_);
  combine(family_->obstacle_geom >= 0, touched_obstacle_ ? 0.0 : 1.0);
  absl::StatusOr<Fitness> fitness = fitness_.Finish(constraint);
  return fitness.ok() ? fitness->value : 0.0;
}

void FamilyEpisode::WriteGoal(int last_frame, float* goal) const {
  for (size_t i = 0; i < a_.size(); ++i) {
    const ParamRange& range = family_->ranges[i];
    goal[i] = range.hi > range.lo ? static_cast<float>((a_[i] - range.lo) / (range.hi - range.lo)) : 0.f;
  }
  goal[a_.size()] = last_frame > 0 ? static_cast<float>(phase_ / last_frame) : 0.f;
}

}  // namespace modskill
