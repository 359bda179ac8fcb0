// The Simulate RPC: a session's life in phases: open (config, motions, batch), describe it to
// the client, then one step per actions message until the client leaves or sends bad input.
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/grpc_status.h"
#include "common/log.h"
#include "common/status_text.h"
#include "common/wire/tensor_codec.h"
#include "server/service/proto_conversions.h"
#include "server/service/session_config_validation.h"
#include "server/service/simulation_service.h"

namespace modskill {

// Buffers one session's step loop reuses from message to message.
struct SimulationService::StepScratch {
  std::vector<float> actions;
  std::vector<float> family_params;
  std::vector<double> clip_weights;  // swapped with the session's pending weights
  std::optional<PendingMotionSet> motion_set;
  std::vector<std::string> part_names;
};

namespace {

void LogSessionClosed(const SimulationSession& session, const char* ending, const grpc::Status& result) {
  const EnvBatch& envs = *session.batch;
  const double seconds = absl::ToDoubleSeconds(absl::Now() - session.opened);
  LogLine("session %s closed (%s%s%s): %lld steps x %d envs in %.1f s, %.0f env steps/s, %lld episodes, "
          "%lld physics resets, %lld failure reports",
          session.id, ending, result.ok() ? "" : ": ", result.error_message(), static_cast<long long>(session.steps),
          envs.num_envs(), seconds, seconds > 0 ? session.steps * envs.num_envs() / seconds : 0.0,
          static_cast<long long>(session.episodes), static_cast<long long>(session.physics_resets),
          static_cast<long long>(session.failure_reports));
}

}  // namespace

grpc::Status SimulationService::Simulate(grpc::ServerContext* context,
                                         grpc::ServerReaderWriter<v1::SimulateResponse, v1::SimulateRequest>* stream) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  v1::SimulateRequest request;
  if (!stream->Read(&request)) return CappedStatus(grpc::StatusCode::INVALID_ARGUMENT, "config: the stream ended before it");
  if (!request.has_config()) {
    return CappedStatus(grpc::StatusCode::INVALID_ARGUMENT, "config: the first message must carry the session config");
  }
  int amp_frames = 0;
  auto opened = OpenSession(*context, request.config(), &amp_frames);
  if (!opened.ok()) return ToGrpcStatus(opened.status());
  SimulationSession& session = **opened;

  // The same messages are reused for every step so that their buffers keep their capacity.
  v1::SimulateResponse response;
  DescribeOpenedSession(session, amp_frames, response.mutable_opened());
  grpc::Status result = grpc::Status::OK;
  const char* ending = "client closed the stream";
  if (!stream->Write(response)) {
    ending = "client went away";
  } else {
    StepScratch scratch;
    scratch.part_names = session.batch->spec().layout.PartNames();
    response.mutable_step();  // switch the oneof once; its tensors are then reused
    while (stream->Read(&request)) {
      if (absl::Status status = StepSession(session, request, amp_frames, scratch, response.mutable_step());
          !status.ok()) {
        result = ToGrpcStatus(status);
        break;
      }
      if (!stream->Write(response)) {
        ending = "client went away";
        break;
      }
    }
  }
  if (!result.ok()) ending = "error";
  LogSessionClosed(session, ending, result);
  registry_.Close(session.id);
  return result;
}

absl::StatusOr<std::shared_ptr<SimulationSession>> SimulationService::OpenSession(const grpc::ServerContext& context,
                                                                                  const v1::SessionConfig& config,
                                                                                  int* amp_frames) {
  auto settings = ParseSessionConfig(config, options_.max_envs_per_session, options_.max_library_clips, *layouts_);
  if (!settings.ok()) return settings.status();
  *amp_frames = settings->amp_frames;
  std::shared_ptr<const MotionLibrary> motions = motions_.Snapshot();
  if (config.motions_size() > 0) {
    auto subset = motions->Subset({config.motions().begin(), config.motions().end()});
    if (!subset.ok()) return subset.status();
    motions = std::make_shared<const MotionLibrary>(*std::move(subset));
  }
  auto session_id = registry_.Reserve();
  if (!session_id.ok()) return session_id.status();
  EnvBatchConfig batch_config;
  batch_config.num_envs = settings->num_envs;
  batch_config.num_threads = options_.threads_per_session;
  batch_config.seed = settings->seed;
  batch_config.env = settings->env;
  auto batch = EnvBatch::Create(batch_config, humanoid_, settings->layout, motions);
  if (!batch.ok()) {
    registry_.Release();
    return batch.status();
  }
  auto session = std::make_shared<SimulationSession>(*session_id, context.peer(), *std::move(batch),
                                                     options_.sampling, options_.sampling_floor, options_.generation,
                                                     config.seed());
  registry_.Register(session);
  LogLine("session %s opened by %s: %d envs, %d clips, layout %s, task %s", session->id, session->peer,
          session->batch->num_envs(), motions->size(), settings->layout.name, TaskInfoOf(settings->env.task).name);
  session->batch->Reset();
  return session;
}

void SimulationService::DescribeOpenedSession(const SimulationSession& session, int amp_frames,
                                              v1::SessionOpened* opened) const {
  const EnvBatch& envs = *session.batch;
  opened->set_session_id(session.id);
  ToProto(envs.spec(), *humanoid_, opened->mutable_spec());
  opened->mutable_spec()->set_num_motions(envs.motions().size());
  for (const std::string& name : session.clip_names) opened->add_clip_names(name);
  FillStepResult(envs, 0, amp_frames, opened->mutable_initial());
}

absl::Status SimulationService::StepSession(SimulationSession& session, const v1::SimulateRequest& request,
                                            int amp_frames, StepScratch& scratch, v1::StepResult* out) {
  EnvBatch& envs = *session.batch;
  const int64_t n = envs.num_envs(), action_size = envs.spec().action_size;
  if (!request.has_actions()) {
    return absl::InvalidArgumentError("actions: every message after the config carries actions");
  }
  if (absl::Status status = ReadFloatTensor(request.actions(), "actions", {n, action_size}, &scratch.actions);
      !status.ok()) {
    return status;
  }
  if (request.termination_distance() != 0 && request.termination_distance() != envs.env_config().termination_distance) {
    if (absl::Status status = envs.SetTerminationDistance(request.termination_distance()); !status.ok()) return status;
  }
  if (request.has_family_params()) {
    const int64_t dims = static_cast<int64_t>(envs.spec().family.size());
    if (dims == 0) return absl::FailedPreconditionError("family_params: the session is not a family session");
    if (absl::Status status = ReadFloatTensor(request.family_params(), "family_params", {n, dims}, &scratch.family_params);
        !status.ok()) {
      return status;
    }
    if (absl::Status status = envs.SetFamilyParameters(scratch.family_params); !status.ok()) return status;
  }
  // New sampling weights (ReportFailures) and clips (generation rounds) take effect here,
  // between two steps: this thread alone steps the batch, so no env is drawing a clip meanwhile.
  out->clear_motion_set_update();
  if (session.TakePending(&scratch.clip_weights, &scratch.motion_set)) {
    const std::optional<PendingMotionSet>& set = scratch.motion_set;
    const absl::Status status = set.has_value()
                                    ? envs.SetMotions(set->library, set->clip_ids, set->reference_amp, scratch.clip_weights)
                                    : envs.SetClipWeights(scratch.clip_weights);
    if (!status.ok()) return absl::InternalError(absl::StrCat("sampler: ", status.message()));
    if (set.has_value()) ToProto(scratch.part_names, *set, out->mutable_motion_set_update());
  }
  if (absl::Status status = envs.Step(scratch.actions); !status.ok()) return status;
  int64_t episodes = 0;
  for (uint8_t done : envs.buffers().done) episodes += done;
  const int64_t physics_resets = envs.physics_resets() - session.physics_resets;
  session.physics_resets += physics_resets;
  session.episodes += episodes;
  registry_.AddSteps(n, episodes, physics_resets);
  FillStepResult(envs, ++session.steps, amp_frames, out);
  return absl::OkStatus();
}

}  // namespace modskill
