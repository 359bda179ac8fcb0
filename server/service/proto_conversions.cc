#include "server/service/proto_conversions.h"

#include <cstring>

#include "server/service/tensor_codec.h"

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
  }
  out->set_obs_size(spec.obs_size);
  out->set_self_obs_size(spec.self_obs_size);
  out->set_task_obs_size(spec.task_obs_size);
  out->set_action_size(spec.action_size);
  out->set_amp_obs_per_frame(spec.amp_obs_per_frame);
  out->set_amp_history(kAmpHistory);
  for (const std::string& name : bodies) out->add_body_names(name);
  for (const std::string& name : spec.joint_names) out->add_joint_names(name);
  out->set_control_dt(spec.control_dt);
  for (int t = 0; t < kNumRewardTerms; ++t) out->add_reward_terms(RewardTermName(t));
  for (int hinge : spec.action_hinge) {
    out->add_action_offset(static_cast<float>(humanoid.action_offset()[hinge]));
    out->add_action_scale(static_cast<float>(humanoid.action_scale()[hinge]));
  }
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
}

void FillStepResult(const EnvBatch& batch, int64_t step, int amp_frames, v1::StepResult* out) {
  const BatchBuffers& b = batch.buffers();
  const int64_t n = batch.num_envs();
  const EnvSpec& spec = batch.spec();
  out->set_step(step);
  SetFloatTensor({n, spec.obs_size}, b.obs.data(), out->mutable_obs());
  if (amp_frames == kAmpHistory) {
    SetFloatTensor({n, spec.amp_obs_size}, b.amp_obs.data(), out->mutable_amp_obs());
  } else if (amp_frames == 1) {
    // The newest frame of each row: a strided gather.
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
  SetFloatTensor({n}, b.reward.data(), out->mutable_reward());
  SetFloatTensor({n, kNumRewardTerms}, b.reward_terms.data(), out->mutable_reward_terms());
  SetUint8Tensor({n}, b.done.data(), out->mutable_done());
  SetUint8Tensor({n}, b.truncated.data(), out->mutable_truncated());
  SetInt32Tensor({n}, b.clip_id.data(), out->mutable_clip_id());
  SetInt32Tensor({n}, b.frame.data(), out->mutable_frame());
  SetInt32Tensor({n}, b.ended_clip_id.data(), out->mutable_ended_clip_id());
  SetInt32Tensor({n}, b.ended_frame.data(), out->mutable_ended_frame());
  SetFloatTensor({n}, b.max_body_error.data(), out->mutable_max_body_error());
  SetFloatTensor({n}, b.mean_body_error.data(), out->mutable_mean_body_error());
  SetFloatTensor({n, b.num_parts}, b.part_error.data(), out->mutable_part_error());
}

}  // namespace modskill
