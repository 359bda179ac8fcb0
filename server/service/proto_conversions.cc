#include "server/service/proto_conversions.h"

#include <cstring>
#include <initializer_list>
#include <type_traits>

#include "common/viewer/viewer_wire.h"
#include "common/wire/physics_wire.h"
#include "common/wire/tensor_codec.h"
#include "server/core/env/episode_end.h"
#include "server/core/env/family_episode.h"
#include "server/core/motion/clip_view.h"

namespace modskill {

void ToProto(const EnvSpec& spec, const HumanoidModel& humanoid, v1::EnvSpec* out) {
  out->set_part_layout(spec.layout.name);
  const std::vector<std::string>& bodies = spec.body_names;
  for (size_t p = 0; p < spec.layout.parts.size(); ++p) {
    v1::BodyPart* part = out->add_parts();
    part->set_name(spec.layout.parts[p].name);
    for (int b : spec.layout.parts[p].bodies) part->add_bodies(bodies[b]);
    part->mutable_obs()->set_start(spec.part_obs[p].start);
    part->mutable_obs()->set_size(spec.part_obs[p].size);
    part->mutable_action()->set_start(spec.part_action[p].start);
    part->mutable_action()->set_size(spec.part_action[p].size);
    for (int b : spec.layout.parts[p].bodies) {
      v1::Slice* self = part->add_self_obs();
      self->set_start(spec.body_obs_start[b]);
      self->set_size(b == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody);
    }
  }
  out->set_obs_size(spec.obs_size);
  out->set_self_obs_size(spec.self_obs_size);
  out->set_task_obs_size(spec.task_obs_size);
  out->set_reference_frames(spec.reference_frames);
  out->set_action_size(spec.action_size);
  out->set_amp_obs_per_frame(spec.amp_obs_per_frame);
  out->set_amp_history(kAmpHistory);
  for (const std::string& name : bodies) out->add_body_names(name);
  for (const std::string& name : spec.joint_names) out->add_joint_names(name);
  out->set_control_dt(spec.control_dt);
  ToWire(spec.physics, out->mutable_physics());
  for (const std::string& term : spec.reward_terms) out->add_reward_terms(term);
  out->set_task(TaskInfoOf(spec.task).name);
  out->mutable_goal_obs()->set_start(spec.goal_obs.start);
  out->mutable_goal_obs()->set_size(spec.goal_obs.size);
  for (const TaskInfo& task : AllTasks()) {
    v1::TaskInfo* info = out->add_tasks();
    info->set_name(task.name);
    info->set_goal_size(task.goal_size);
    for (const std::string& term : task.reward_terms) info->add_reward_terms(term);
    info->set_description(task.description);
    for (const std::string& body : task.tracked_bodies) info->add_tracked_bodies(body);
  }
  for (int hinge : spec.action_hinge) {
    out->add_action_offset(static_cast<float>(humanoid.action_offset()[hinge]));
    out->add_action_scale(static_cast<float>(humanoid.action_scale()[hinge]));
  }
  for (const ViewerBody& body : ViewerBodiesFromSpec(humanoid.spec())) ToWire(body, out->add_body_geometry());
  for (const FamilyParameterInfo& parameter : OfferedFamilyParameters()) {
    v1::FamilyParameterInfo* info = out->add_family_parameters();
    info->set_name(parameter.name);
    info->set_unit(parameter.unit);
    info->set_description(parameter.description);
    info->set_min_value(parameter.min_value);
    info->set_min_exclusive(parameter.min_exclusive);
  }
  for (const ParamRange& range : spec.family) {
    v1::FamilyParameterRange* wire = out->add_family();
    wire->set_name(range.name);
    wire->set_lo(range.lo);
    wire->set_hi(range.hi);
  }
  out->set_time_warp_action(spec.time_warp_action);
}

void ToProto(const MotionClip& clip, v1::MotionInfo* out) {
  out->set_name(clip.name);
  out->set_frames(clip.num_frames);
  out->set_fps(clip.fps);
  out->set_duration(clip.duration());
  out->set_label(clip.label);
  out->set_humanml3d_id(clip.humanml3d_id);
  out->set_source(clip.source);
}

void ToProto(const ClipRolloutMetrics& metrics, v1::ClipMetrics* out) {
  out->set_clip(metrics.clip);
  out->set_success(metrics.success);
  out->set_steps(metrics.steps);
  out->set_g_mpjpe_mm(metrics.g_mpjpe_mm);
  out->set_mpjpe_mm(metrics.mpjpe_mm);
  out->set_acc_error_mm(metrics.acc_error_mm);
  out->set_vel_error_mm(metrics.vel_error_mm);
  for (double e : metrics.body_error_mm) out->add_body_error_mm(e);
  for (double e : metrics.part_error_mm) out->add_part_error_mm(e);
  out->set_max_mean_body_error_m(metrics.worst_mean_body_error);
  out->set_normalized_return(metrics.normalized_return);
  if (metrics.has_family) {
    // The parameters' names are the checkpoint's: the Rollout RPC fills family.params.
    v1::FamilyRolloutReport* family = out->mutable_family();
    family->set_fitness(metrics.fitness);
    family->set_apex_height_m(metrics.family.apex_height);
    family->set_highest_effector_m(metrics.family.highest_effector);
    family->set_flight_s(metrics.family.flight_s);
    family->set_reached_end(metrics.reached_end);
    family->set_final_phase(metrics.final_phase);
  }
}

void ToProto(const std::vector<std::string>& part_names, const VariantProvenance& provenance,
             v1::ClipProvenance* out) {
  out->set_parent(provenance.parent);
  out->set_generator(provenance.generator);
  if (provenance.part >= 0 && provenance.part < static_cast<int>(part_names.size())) {
    out->set_part(part_names[provenance.part]);
  }
  out->set_seed(provenance.seed);
}

// The clips that joined and left since the stream last installed a motion set.
void ToProto(const std::vector<std::string>& part_names, const PendingMotionSet& pending, v1::MotionSetUpdate* out) {
  for (const SessionClipInfo& info : pending.added) {
    v1::SessionClip* clip = out->add_added();
    clip->set_clip_id(info.id);
    clip->set_name(info.name);
    if (info.provenance.has_value()) ToProto(part_names, *info.provenance, clip->mutable_provenance());
  }
  for (int id : pending.removed_ids) out->add_removed_clip_ids(id);
}

namespace {

// One field of the step result: [n] when the table says kVector, else [n, width].
template <typename T>
void EncodeRows(const std::vector<T>& rows, int64_t n, int64_t width, v1::Tensor* out) {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, int32_t> || std::is_same_v<T, uint8_t>);
  const auto set = [&](std::initializer_list<int64_t> shape) {
    if constexpr (std::is_same_v<T, float>) {
      SetFloatTensor(shape, rows.data(), out);
    } else if constexpr (std::is_same_v<T, int32_t>) {
      SetInt32Tensor(shape, rows.data(), out);
    } else {
      SetUint8Tensor(shape, rows.data(), out);
    }
  };
  width == StepResultWidths::kVector ? set({n}) : set({n, width});
}

// amp_obs as the session asked: the whole history, the newest frame of each row (a strided
// gather) or nothing.
void EncodeAmpObs(const BatchBuffers& b, const EnvSpec& spec, int amp_frames, v1::StepResult* out) {
  const int64_t n = b.num_envs;
  if (amp_frames == kAmpHistory) {
    SetFloatTensor({n, spec.amp_obs_size}, b.amp_obs.data(), out->mutable_amp_obs());
  } else if (amp_frames == 1) {
    std::string* data = out->mutable_amp_obs()->mutable_data();
    data->resize(n * spec.amp_obs_per_frame * sizeof(float));
    for (int64_t i = 0; i < n; ++i) {
      std::memcpy(&(*data)[i * spec.amp_obs_per_frame * sizeof(float)], &b.amp_obs[i * spec.amp_obs_size],
                  spec.amp_obs_per_frame * sizeof(float));
    }
    out->mutable_amp_obs()->clear_shape();
    out->mutable_amp_obs()->add_shape(n);
    out->mutable_amp_obs()->add_shape(spec.amp_obs_per_frame);
    out->mutable_amp_obs()->set_dtype(v1::FLOAT32);
  } else {
    out->clear_amp_obs();
  }
}

// StepResult.end_cause ships EpisodeEnd's values as they are.
static_assert(static_cast<int>(EpisodeEnd::kTime) == v1::END_CAUSE_TIME &&
              static_cast<int>(EpisodeEnd::kTracking) == v1::END_CAUSE_TRACKING &&
              static_cast<int>(EpisodeEnd::kFall) == v1::END_CAUSE_FALL &&
              static_cast<int>(EpisodeEnd::kTask) == v1::END_CAUSE_TASK &&
              static_cast<int>(EpisodeEnd::kBlowUp) == v1::END_CAUSE_BLOW_UP);

}  // namespace

void FillStepResult(const EnvBatch& batch, int64_t step, int amp_frames, v1::StepResult* out) {
  const BatchBuffers& b = batch.buffers();
  const int64_t n = batch.num_envs();
  out->set_step(step);
  // Every field of the table, amp_obs in the form the session asked for, the family's fields in
  // family sessions only.
#define MODSKILL_ENCODE_FIELD(name, type, dtype, width, initial, presence)                      \
  if (StepResultPresence::presence == StepResultPresence::kWhenRequested) {                    \
    EncodeAmpObs(b, batch.spec(), amp_frames, out);                                            \
  } else if (StepResultPresence::presence != StepResultPresence::kFamily || b.widths.family_params > 0) { \
    EncodeRows(b.name, n, b.widths.width, out->mutable_##name());                              \
  }
  MODSKILL_STEP_RESULT_FIELDS(MODSKILL_ENCODE_FIELD)
#undef MODSKILL_ENCODE_FIELD
}

}  // namespace modskill
