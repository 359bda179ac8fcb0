// The Rollout RPC in phases: load the policy (a path inside --checkpoint_dir, or bytes), check it
// fits this server's env and the request's action mode, resolve the clips and options, run the
// clips (plainly, with each frame's z, or composed: skill_rollout.h), stream frames when asked
// and one metrics message per clip.
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/grpc_status.h"
#include "common/log.h"
#include "common/shown_value.h"
#include "common/wire/policy_enums.h"
#include "common/wire/tensor_codec.h"
#include "server/core/env/family_episode.h"
#include "server/core/env/policy_fit.h"
#include "server/core/util/confined_path.h"
#include "server/service/family_request.h"
#include "server/service/proto_conversions.h"
#include "server/service/session_config_validation.h"
#include "server/service/simulation_service.h"
#include "server/service/skill_rollout.h"

namespace modskill {
namespace {

// The request's action mode (unspecified: the trained one) must be the one the policy was
// trained in.
absl::Status CheckActionMode(const v1::RolloutRequest& request, const ActionMapping& trained) {
  if (!v1::ActionMode_IsValid(request.action_mode())) {
    return absl::InvalidArgumentError(absl::StrCat("action_mode: unknown value ", static_cast<int>(request.action_mode())));
  }
  if (request.action_mode() != v1::ACTION_MODE_UNSPECIFIED && request.action_mode() != ToWire(trained.mode)) {
    return absl::FailedPreconditionError(absl::StrCat("action_mode: the checkpoint was trained in ",
                                                      ActionModeName(trained.mode), " mode; it cannot run in ",
                                                      v1::ActionMode_Name(request.action_mode())));
  }
  return absl::OkStatus();
}

// The task the checkpoint was trained for; a request that names another is refused.
absl::StatusOr<TaskKind> RolloutTask(const v1::RolloutRequest& request, const PolicySpec& trained) {
  absl::StatusOr<TaskKind> task = ParseTask(trained.task);
  if (!task.ok()) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: trained for task '", ShownValue(trained.task),
                                                      "' that this server does not offer"));
  }
  if (!request.task().empty() && request.task() != TaskInfoOf(*task).name) {
    return absl::FailedPreconditionError(absl::StrCat("task: the checkpoint was trained for ", TaskInfoOf(*task).name,
                                                      "; it cannot run ", ShownValue(request.task())));
  }
  return task;
}

// The library ids of the requested clips; none requested: every clip.
absl::StatusOr<std::vector<int>> RolloutClipIds(const v1::RolloutRequest& request, const MotionLibrary& motions) {
  std::vector<int> clip_ids;
  for (int c = 0; c < request.clips_size(); ++c) {
    const int id = motions.Find(request.clips(c));
    if (id < 0) {
      return absl::NotFoundError(absl::StrCat("clips[", c, "]: unknown clip '", ShownValue(request.clips(c)), "'"));
    }
    clip_ids.push_back(id);
  }
  if (clip_ids.empty()) {
    for (int c = 0; c < motions.size(); ++c) clip_ids.push_back(c);
  }
  return clip_ids;
}

// A motor-skill family's policy runs its one clip, as a family env at the request's a (`a`, as
// given; the envs run it as float32); without an asked-for termination it ends as in training (a
// fall, or a body 1 m off the warped clip).
absl::Status UseFamily(const v1::RolloutRequest& request, const PolicySpec& trained,
                       std::shared_ptr<const MotionLibrary>* motions, RolloutOptions* options, std::vector<double>* a) {
  if (!trained.is_family()) {
    if (request.family_params().empty()) return absl::OkStatus();
    return absl::FailedPreconditionError(
        "family_params: the checkpoint is not a motor-skill family's policy (modskill-learner --family exports one)");
  }
  if (absl::Status status = ValidateFamilyRanges(trained.family, "checkpoint family"); !status.ok()) {
    return absl::FailedPreconditionError(status.message());
  }
  for (int c = 0; c < request.clips_size(); ++c) {
    if (request.clips(c) != trained.family_clip) {
      return absl::InvalidArgumentError(absl::StrCat("clips[", c, "]: the checkpoint is the family of '",
                                                     ShownValue(trained.family_clip), "' and runs that clip only"));
    }
  }
  auto clip = (*motions)->Subset({trained.family_clip});
  if (!clip.ok()) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: the family's clip '", ShownValue(trained.family_clip),
                                                      "' is not in this server's library"));
  }
  if (clip->clip(0).num_frames != trained.family_frames) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: the family's clip '", ShownValue(trained.family_clip),
                                                      "' had ", trained.family_frames, " frames; this server's has ",
                                                      clip->clip(0).num_frames));
  }
  auto resolved = ResolveFamilyParams(trained.family, request.family_params(), "family_params");
  if (!resolved.ok()) return resolved.status();
  *a = *std::move(resolved);
  *motions = std::make_shared<const MotionLibrary>(*std::move(clip));
  options->family = trained.family;
  options->family_params.assign(a->begin(), a->end());
  if (request.termination() == v1::TERMINATION_UNSPECIFIED) {
    options->termination = TerminationMode::kTraining;
    options->termination_distance =
        request.termination_distance() > 0 ? request.termination_distance() : kFamilyDefaultTerminationDistance;
  }
  return absl::OkStatus();
}

// Writes one RolloutFrame per simulated frame until the client goes away.
class FrameStreamer {
 public:
  FrameStreamer(grpc::ServerWriter<v1::RolloutResponse>* writer, const MotionLibrary& motions,
                const std::vector<int>& clip_ids)
      : writer_(writer), motions_(motions), clip_ids_(clip_ids) {}

  bool client_gone() const { return client_gone_; }

  void Write(const RolloutFrameView& view) {
    if (client_gone_) return;
    v1::RolloutFrame* out = message_.mutable_frame();
    out->set_clip(motions_.clip(clip_ids_[view.clip_index]).name);
    out->set_frame(view.frame);
    const int64_t bodies = static_cast<int64_t>(view.sim.body_pos.size());
    WritePoses(view.sim, bodies, out->mutable_sim_body_pos(), out->mutable_sim_body_rot());
    WritePoses(view.ref, bodies, out->mutable_ref_body_pos(), out->mutable_ref_body_rot());
    out->set_mean_body_error_m(static_cast<float>(view.mean_body_error));
    out->set_done(view.done);
    out->set_terminated(view.terminated);
    out->clear_skill_z();
    if (view.skill_z != nullptr && skill_shape_[0] > 0) {
      SetFloatTensor({skill_shape_[0], skill_shape_[1]}, view.skill_z, out->mutable_skill_z());
    }
    client_gone_ = !writer_->Write(message_);
  }

  // Frames carry z [parts, embed_dim] from now on (RolloutRequest.record_skills).
  void set_skill_shape(int64_t parts, int64_t embed_dim) { skill_shape_ = {parts, embed_dim}; }

 private:
  grpc::ServerWriter<v1::RolloutResponse>* writer_;
  const MotionLibrary& motions_;
  const std::vector<int>& clip_ids_;
  // Positions [bodies, 3] and rotations [bodies, 4] (w x y z) as float32.
  void WritePoses(const HumanoidState& state, int64_t bodies, v1::Tensor* pos, v1::Tensor* rot) {
    flat_.clear();
    for (const Vec3& p : state.body_pos) flat_.insert(flat_.end(), {float(p.x()), float(p.y()), float(p.z())});
    SetFloatTensor({bodies, 3}, flat_.data(), pos);
    flat_.clear();
    for (const Quat& q : state.body_rot) {
      flat_.insert(flat_.end(), {float(q.w()), float(q.x()), float(q.y()), float(q.z())});
    }
    SetFloatTensor({bodies, 4}, flat_.data(), rot);
  }

  v1::RolloutResponse message_;
  std::vector<float> flat_;
  std::array<int64_t, 2> skill_shape_{0, 0};
  bool client_gone_ = false;
};

// One Rollout's resolved inputs.
struct RolloutRun {
  std::shared_ptr<const HumanoidModel> humanoid;
  const PartLayout* layout;
  std::shared_ptr<const MotionLibrary> motions;
  std::vector<int> clip_ids;
  PolicyCheckpoint* checkpoint;
  RolloutOptions options;
  RolloutFrameCallback on_frame;
  std::function<absl::Status()> check;  // fails once the client went away
};

std::vector<v1::ClipMetrics> ToWire(const std::vector<ClipRolloutMetrics>& metrics) {
  std::vector<v1::ClipMetrics> out(metrics.size());
  for (size_t i = 0; i < metrics.size(); ++i) ToProto(metrics[i], &out[i]);
  return out;
}

// A plain rollout (forward), one with each frame's z (record_skills), or a composition.
absl::StatusOr<std::vector<v1::ClipMetrics>> RunRequested(const v1::RolloutRequest& request, RolloutRun& run) {
  if (request.has_composition()) {
    auto composition = ToComposition(request.composition(), *run.layout, *run.motions);
    if (!composition.ok()) return composition.status();
    auto result = RunComposedRollout(run.humanoid, *run.layout, run.motions, SkillPolicyOf(*run.checkpoint, run.check),
                                     *composition, run.options, run.on_frame);
    if (!result.ok()) return result.status();
    std::vector<v1::ClipMetrics> out = ToWire({result->metrics});
    ToProto(*result, *composition, *run.layout, *run.motions, out[0].mutable_composition());
    return out;
  }
  absl::StatusOr<std::vector<ClipRolloutMetrics>> metrics;
  if (request.record_skills()) {
    metrics = RunSkillRollout(run.humanoid, *run.layout, run.motions, run.clip_ids,
                              SkillPolicyOf(*run.checkpoint, run.check), run.options, run.on_frame);
  } else {
    PolicyCheckpoint* checkpoint = run.checkpoint;
    metrics = RunRollout(
        run.humanoid, *run.layout, run.motions, run.clip_ids,
        [&](const float* obs, int n, float* actions) -> absl::Status {
          if (absl::Status status = run.check(); !status.ok()) return status;
          return checkpoint->Act(obs, n, actions);
        },
        run.options, run.on_frame);
  }
  if (!metrics.ok()) return metrics.status();
  return ToWire(*metrics);
}

}  // namespace

grpc::Status SimulationService::Rollout(grpc::ServerContext* context, const v1::RolloutRequest* request,
                                        grpc::ServerWriter<v1::RolloutResponse>* writer) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> policy = LoadRolloutPolicy(*request);
  if (!policy.ok()) return ToGrpcStatus(policy.status());
  const PolicySpec& trained = (*policy)->spec();
  auto layout = Layout(trained.part_layout);
  if (!layout.ok()) {
    return ToGrpcStatus(absl::FailedPreconditionError(absl::StrCat(
        "checkpoint: trained with layout '", ShownValue(trained.part_layout), "' that this server does not offer")));
  }
  absl::StatusOr<TaskKind> task = RolloutTask(*request, trained);
  if (!task.ok()) return ToGrpcStatus(task.status());
  EnvSpec env_spec = MakeEnvSpec(*humanoid_, *layout, *task, trained.reference_frames);
  if (trained.is_family()) AddFamilyToSpec(trained.family, &env_spec);
  if (absl::Status status = CheckPolicyFitsEnv(trained, env_spec, TaskInfoOf(*task).name); !status.ok()) {
    return ToGrpcStatus(status);
  }
  if (absl::Status status = CheckActionMode(*request, trained.action); !status.ok()) return ToGrpcStatus(status);
  absl::StatusOr<RolloutOptions> options = RolloutOptionsFor(*request, trained.action);
  if (!options.ok()) return ToGrpcStatus(options.status());
  options->task = *task;
  options->reference_frames = env_spec.reference_frames;
  if (absl::Status status = CheckSkillRequest(*request, **policy, *task); !status.ok()) return ToGrpcStatus(status);
  std::shared_ptr<const MotionLibrary> motions = motions_.Snapshot();
  std::vector<double> family_a;
  if (absl::Status status = UseFamily(*request, trained, &motions, &*options, &family_a); !status.ok()) {
    return ToGrpcStatus(status);
  }
  absl::StatusOr<std::vector<int>> clip_ids = RolloutClipIds(*request, *motions);
  if (!clip_ids.ok()) return ToGrpcStatus(clip_ids.status());
  if (request->has_composition()) clip_ids = std::vector<int>{motions->Find(request->composition().base_clip())};

  FrameStreamer frames(writer, *motions, *clip_ids);
  if (request->record_skills()) frames.set_skill_shape((*policy)->skill_parts(), (*policy)->embed_dim());
  RolloutRun run{humanoid_, &*layout, motions, *clip_ids, policy->get(), *options, nullptr, nullptr};
  if (request->stream_frames()) {
    run.on_frame = [&frames](const RolloutFrameView& view) { frames.Write(view); };
  }
  run.check = [&]() -> absl::Status {
    if (context->IsCancelled() || frames.client_gone()) return absl::CancelledError("rollout: the client went away");
    return absl::OkStatus();
  };
  auto metrics = RunRequested(*request, run);
  if (!metrics.ok()) return ToGrpcStatus(metrics.status());
  int successes = 0;
  for (v1::ClipMetrics& clip : *metrics) {
    if (trained.is_family()) SetFamilyParams(trained.family, family_a, clip.mutable_family()->mutable_params());
    v1::RolloutResponse message;
    *message.mutable_metrics() = clip;
    successes += clip.success();
    if (!writer->Write(message)) break;
  }
  LogLine("rollout by %s: %d clips, %d succeeded", context->peer(), static_cast<int>(metrics->size()), successes);
  return grpc::Status::OK;
}

absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> SimulationService::LoadRolloutPolicy(
    const v1::RolloutRequest& request) const {
  return LoadPolicy(request.has_checkpoint_path() ? &request.checkpoint_path() : nullptr,
                    request.has_checkpoint_bytes() ? &request.checkpoint_bytes() : nullptr);
}

absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> SimulationService::LoadPolicy(const std::string* path,
                                                                                const std::string* bytes) const {
  if (path != nullptr) {
    // Only files in the operator's --checkpoint_dir directories, and no larger than an upload.
    auto read = ReadConfinedFile(options_.checkpoint_dirs, *path, options_.max_upload_bytes, "checkpoint_path");
    if (!read.ok()) return read.status();
    return PolicyCheckpoint::LoadBytes(*read);
  }
  if (bytes != nullptr) return PolicyCheckpoint::LoadBytes(*bytes);
  return absl::InvalidArgumentError("checkpoint: set checkpoint_path or checkpoint_bytes");
}

absl::StatusOr<RolloutOptions> SimulationService::RolloutOptionsFor(const v1::RolloutRequest& request,
                                                                    const ActionMapping& trained) const {
  if (request.max_steps_per_clip() < 0) return absl::InvalidArgumentError("max_steps_per_clip: < 0");
  auto termination = ToTermination(request.termination(), v1::EVALUATION);
  if (!termination.ok()) return termination.status();
  auto distance = ToTerminationDistance(request.termination_distance(), *termination);
  if (!distance.ok()) return distance.status();
  RolloutOptions options;
  options.termination = *termination;
  options.termination_distance = *distance;
  options.action = trained;
  options.max_steps_per_clip = request.max_steps_per_clip();
  auto task_settings = ToTaskSettings(request.task_settings());
  if (!task_settings.ok()) return task_settings.status();
  options.task_settings = *task_settings;
  options.seed = request.seed();
  options.num_threads = options_.threads_per_session;
  options.physics = options_.physics;
  return options;
}

}  // namespace modskill
