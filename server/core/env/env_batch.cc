#include "server/core/env/env_batch.h"

#include <algorithm>
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/policy/reference_frames.h"
#include "server/core/env/task_catalog.h"
#include "server/core/sim/mjcf_builder.h"
#include "server/core/util/seed_mixing.h"

namespace modskill {
namespace {

// What the envs of a batch share for their task: the bodies termination watches, the VR bodies,
// the goal tasks' context and the fall check.
void SetUpTask(EnvContext& context) {
  const HumanoidSpec& body_spec = context.humanoid->spec();
  context.vr_body_ids = TrackedBodyIndices(TaskKind::kVrTracking, body_spec);
  const std::vector<int> feet = FootBodies(body_spec);
  for (int b = 0; b < context.humanoid->num_bodies(); ++b) {
    const bool foot = std::find(feet.begin(), feet.end(), b) != feet.end();
    if (context.config.termination_bodies == TerminationBodies::kAll || !foot) context.termination_body_ids.push_back(b);
  }
  // VR tracking fails when the tracked points drift, whatever the rest of the body does.
  if (context.config.task == TaskKind::kVrTracking) context.termination_body_ids = context.vr_body_ids;
  context.goal_task.settings = context.config.task_settings;
  context.goal_task.control_dt = context.spec->control_dt;
  context.goal_task.right_hand = body_spec.BodyIndex("R_Hand");
  context.fall_detector = std::make_shared<const FallDetector>(*context.humanoid);
  const mjModel* model = context.humanoid->model();
  const int joint = mj_name2id(model, mjOBJ_JOINT, kStrikeTargetName);
  if (joint < 0) return;
  context.goal_task.target_qpos = model->jnt_qposadr[joint];
  context.goal_task.target_qvel = model->jnt_dofadr[joint];
  context.goal_task.target_geom = mj_name2id(model, mjOBJ_GEOM, kStrikeTargetName);
  context.goal_task.may_touch_target.assign(model->ngeom, 0);
  context.goal_task.may_touch_target[mj_name2id(model, mjOBJ_GEOM, "floor")] = 1;
  for (const char* name : {"R_Hand", "R_Wrist", "R_Elbow"}) {
    const int body = context.humanoid->mj_body_id(body_spec.BodyIndex(name));
    for (int g = 0; g < model->ngeom; ++g) {
      if (model->geom_bodyid[g] == body) context.goal_task.may_touch_target[g] = 1;
    }
  }
}

// The strike task needs its target in the model, a family with obstacle parameters its obstacle;
// a family also needs stable PD (below). Every other session runs on the model as given.
absl::StatusOr<std::shared_ptr<const HumanoidModel>> ModelForTask(std::shared_ptr<const HumanoidModel> humanoid,
                                                                  const TrackingEnvConfig& env) {
  const bool strike = env.task == TaskKind::kStrike &&
                      mj_name2id(humanoid->model(), mjOBJ_BODY, kStrikeTargetName) < 0;
  const bool obstacle = FamilyNeedsObstacle(env.family) &&
                        mj_name2id(humanoid->model(), mjOBJ_GEOM, kFamilyObstacleName) < 0;
  // Under the paper's torque limits a position servo's damping, MuJoCo joint damping outside the
  // actuator's force range, brakes a knee extending at 5 rad/s with 400 N*m against a 170 N*m
  // limit: the character cannot push off. Stable PD limits the whole PD torque, damping included,
  // as Lee et al.'s servos do (PdControllerTest.StablePdCountsDampingAgainstTheTorqueLimit).
  const bool stable_pd = !env.family.empty() && humanoid->options().pd_mode != PdMode::kStablePd;
  if (!strike && !obstacle && !stable_pd) return humanoid;
  PhysicsOptions physics = humanoid->options();
  physics.strike_target |= strike;
  physics.family_obstacle |= obstacle;
  if (stable_pd) physics.pd_mode = PdMode::kStablePd;
  return HumanoidModel::Create(humanoid->spec(), physics);
}

// A family session: one clip, tracking, residual actions; its context and spec.
absl::Status SetUpFamily(EnvContext& context, EnvSpec* spec) {
  const TrackingEnvConfig& env = context.config;
  if (absl::Status status = ValidateFamilySession(env.family, "family", context.motions->size(), env.task,
                                                  env.action.mode, env.loop_clips);
      !status.ok()) {
    return status;
  }
  auto family = MakeFamilyContext(env.family, context.humanoid, context.motions->clip(0));
  if (!family.ok()) return family.status();
  context.family = *std::move(family);
  // Lee et al. reward tracking and the task only. An energy penalty makes every step of a hard
  // motion (a jump) negative, and a policy then learns to end its episodes early; the column
  // stays, at 0.
  context.config.reward.energy_coefficient = 0;
  // Displacements are not clamped into the joint ranges (ActionMapping::clamp_to_joint_range).
  context.config.action.clamp_to_joint_range = false;
  AddFamilyToSpec(env.family, spec);
  return absl::OkStatus();
}

}  // namespace

absl::Status EnvBatch::SetTerminationDistance(double distance) {
  if (absl::Status status = ValidateTerminationDistance(distance); !status.ok()) return status;
  context_.config.termination_distance = distance;
  return absl::OkStatus();
}

absl::Status CheckReferenceFrames(const TrackingEnvConfig& env) {
  if (absl::Status status = ValidateReferenceFrames(env.reference_frames, "reference_frames"); !status.ok()) {
    return status;
  }
  if (env.reference_frames == 1) return absl::OkStatus();
  const auto refuse = [&](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat("reference_frames: ", env.reference_frames, " ", why));
  };
  if (env.task != TaskKind::kTracking) return refuse(absl::StrCat("for task ", TaskInfoOf(env.task).name, "; tracking only"));
  if (env.loop_clips) return refuse("with loop_clips; only a clip tracked where it is");
  if (env.anchor_reference) return refuse("with anchor_reference; only a clip tracked where it is");
  if (!env.family.empty()) return refuse("in a family session; tracking only");
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<EnvBatch>> EnvBatch::Create(const EnvBatchConfig& config,
                                                           std::shared_ptr<const MotionLibrary> motions) {
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return spec.status();
  auto humanoid = HumanoidModel::Create(*spec, config.physics);
  if (!humanoid.ok()) return humanoid.status();
  auto catalog = PartLayoutCatalog::LoadDefault(*spec);
  if (!catalog.ok()) return catalog.status();
  auto layout = catalog->Get(config.part_layout.empty() ? catalog->default_name() : config.part_layout);
  if (!layout.ok()) return layout.status();
  return Create(config, *std::move(humanoid), *layout, std::move(motions));
}

absl::StatusOr<std::unique_ptr<EnvBatch>> EnvBatch::Create(const EnvBatchConfig& config,
                                                           std::shared_ptr<const HumanoidModel> humanoid,
                                                           const PartLayout& layout,
                                                           std::shared_ptr<const MotionLibrary> motions) {
  if (config.num_envs < 1 || config.num_envs > 65536) {
    return absl::InvalidArgumentError(absl::StrCat("num_envs: ", config.num_envs, " outside [1, 65536]"));
  }
  if (config.num_threads < 1 || config.num_threads > 256) {
    return absl::InvalidArgumentError(absl::StrCat("num_threads: ", config.num_threads, " outside [1, 256]"));
  }
  if (motions == nullptr || motions->size() == 0) return absl::InvalidArgumentError("motions: the library is empty");
  if (absl::Status status = ValidateTerminationDistance(config.env.termination_distance); !status.ok()) return status;
  if (absl::Status status = config.env.action.Validate(); !status.ok()) return status;
  if (absl::Status status = config.env.task_settings.Validate(); !status.ok()) return status;
  if (absl::Status status = CheckReferenceFrames(config.env); !status.ok()) return status;
  for (int c = 0; c < motions->size(); ++c) {
    if (motions->clip(c).num_bodies != humanoid->num_bodies()) {
      return absl::InvalidArgumentError(absl::StrCat("motions: clip '", motions->clip(c).name, "' has ",
                                                     motions->clip(c).num_bodies, " bodies, the humanoid ",
                                                     humanoid->num_bodies()));
    }
  }
  auto task_model = ModelForTask(std::move(humanoid), config.env);
  if (!task_model.ok()) return task_model.status();
  std::unique_ptr<EnvBatch> batch(new EnvBatch());
  batch->context_.humanoid = *std::move(task_model);
  batch->context_.motions = std::move(motions);
  batch->context_.config = config.env;
  EnvSpec spec = MakeEnvSpec(*batch->context_.humanoid, layout, config.env.task, config.env.reference_frames);
  if (!config.env.family.empty()) {
    if (absl::Status status = SetUpFamily(batch->context_, &spec); !status.ok()) return status;
  }
  batch->context_.spec = std::make_shared<const EnvSpec>(std::move(spec));
  SetUpTask(batch->context_);
  batch->context_.reference_amp =
      std::make_shared<const ReferenceAmpFrames>(*batch->context_.spec, *batch->context_.motions);
  batch->sampler_ = ClipSampler(batch->context_.motions->size());
  batch->context_.sampler = &batch->sampler_;
  batch->buffers_.Allocate(*batch->context_.spec, config.num_envs);
  for (int i = 0; i < config.num_envs; ++i) {
    batch->envs_.push_back(std::make_unique<TrackingEnv>(&batch->context_, MixSeed(config.seed * 1000003ull + i)));
  }
  batch->pool_ = std::make_unique<WorkerPool>(std::min(config.num_threads, config.num_envs));
  EnvBatch* self = batch.get();
  const int threads = batch->pool_->num_threads();
  auto range = [self, threads](int thread, int* begin, int* end) {
    const int n = self->num_envs();
    *begin = static_cast<int>(static_cast<int64_t>(n) * thread / threads);
    *end = static_cast<int>(static_cast<int64_t>(n) * (thread + 1) / threads);
  };
  batch->step_work_ = [self, range](int thread) {
    int begin, end;
    range(thread, &begin, &end);
    const int action_size = self->spec().action_size;
    for (int i = begin; i < end; ++i) {
      self->envs_[i]->Step(self->pending_actions_ + static_cast<size_t>(i) * action_size, self->row(i));
    }
  };
  batch->reset_work_ = [self, range](int thread) {
    int begin, end;
    range(thread, &begin, &end);
    for (int i = begin; i < end; ++i) self->envs_[i]->Reset(self->row(i));
  };
  return batch;
}

void EnvBatch::Reset() {
  pool_->Run(reset_work_);
  std::fill(buffers_.done.begin(), buffers_.done.end(), 0);
  std::fill(buffers_.truncated.begin(), buffers_.truncated.end(), 0);
}

absl::Status EnvBatch::Step(absl::Span<const float> actions) {
  const size_t expected = static_cast<size_t>(num_envs()) * spec().action_size;
  if (actions.size() != expected) {
    return absl::InvalidArgumentError(absl::StrCat("actions: ", actions.size(), " values, expected ", num_envs(), " x ",
                                                   spec().action_size, " = ", expected));
  }
  for (size_t k = 0; k < actions.size(); ++k) {
    if (!std::isfinite(actions[k])) {
      return absl::InvalidArgumentError(absl::StrCat("actions: row ", k / spec().action_size, " column ",
                                                     k % spec().action_size, " is ", actions[k]));
    }
  }
  pending_actions_ = actions.data();
  pool_->Run(step_work_);
  pending_actions_ = nullptr;
  ++steps_;
  return absl::OkStatus();
}

absl::Status EnvBatch::SetFamilyParameters(absl::Span<const float> rows) {
  const std::vector<ParamRange>& ranges = spec().family;
  if (ranges.empty()) return absl::FailedPreconditionError("family_params: the session is not a family session");
  const size_t dims = ranges.size();
  if (rows.size() != static_cast<size_t>(num_envs()) * dims) {
    return absl::InvalidArgumentError(absl::StrCat("family_params: ", rows.size(), " values, expected ", num_envs(),
                                                   " x ", dims));
  }
  for (size_t k = 0; k < rows.size(); ++k) {
    const ParamRange& range = ranges[k % dims];
    if (!(rows[k] >= static_cast<float>(range.lo) && rows[k] <= static_cast<float>(range.hi))) {
      return absl::InvalidArgumentError(absl::StrCat("family_params: row ", k / dims, " ", range.name, " = ", rows[k],
                                                     " is outside its range ", range.lo, ":", range.hi));
    }
  }
  for (int i = 0; i < num_envs(); ++i) envs_[i]->SetNextFamilyParameters(&rows[static_cast<size_t>(i) * dims]);
  return absl::OkStatus();
}

absl::Status EnvBatch::SetMotions(std::shared_ptr<const MotionLibrary> motions, std::vector<int> clip_ids,
                                  std::shared_ptr<const ReferenceAmpFrames> reference_amp,
                                  absl::Span<const double> weights) {
  if (context_.family != nullptr) {
    return absl::FailedPreconditionError("motions: a family session keeps its one clip");
  }
  if (motions == nullptr || motions->size() == 0) return absl::InvalidArgumentError("motions: the library is empty");
  if (reference_amp == nullptr) return absl::InvalidArgumentError("reference_amp: missing");
  if (!clip_ids.empty() && static_cast<int>(clip_ids.size()) != motions->size()) {
    return absl::InvalidArgumentError(absl::StrCat("clip_ids: ", clip_ids.size(), " ids for ", motions->size(), " clips"));
  }
  for (int c = 0; c < motions->size(); ++c) {
    if (motions->clip(c).num_bodies != humanoid().num_bodies() || motions->clip(c).num_frames < 2) {
      return absl::InvalidArgumentError(absl::StrCat("motions: clip '", motions->clip(c).name,
                                                     "' does not fit the humanoid or has < 2 frames"));
    }
  }
  ClipSampler sampler(motions->size());
  if (absl::Status status = sampler.SetWeights(weights); !status.ok()) return status;
  sampler_ = std::move(sampler);
  context_.motions = std::move(motions);
  context_.clip_ids = std::move(clip_ids);
  context_.reference_amp = std::move(reference_amp);
  return absl::OkStatus();
}

int64_t EnvBatch::physics_resets() const {
  int64_t total = 0;
  for (const auto& env : envs_) total += env->physics_resets();
  return total;
}

}  // namespace modskill
