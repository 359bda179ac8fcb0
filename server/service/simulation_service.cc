#include "server/service/simulation_service.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/grpc_status.h"
#include "common/log.h"
#include "common/policy/policy_checkpoint.h"
#include "common/shown_value.h"
#include "common/status_text.h"
#include "common/wire/tensor_codec.h"
#include "server/core/env/policy_fit.h"
#include "server/core/motion/clip_file.h"
#include "server/core/motion/motion_import.h"
#include "server/core/util/confined_path.h"
#include "server/service/discriminator_scorer.h"
#include "server/service/proto_conversions.h"
#include "server/service/session_config_validation.h"

namespace modskill {
namespace {

grpc::Status Error(grpc::StatusCode code, const std::string& message) { return CappedStatus(code, message); }

// Constant-time comparison, so a wrong token does not leak its matching prefix length.
bool SameSecret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

v1::ActionMode ToProto(ActionMode mode) { return mode == ActionMode::kResidual ? v1::RESIDUAL : v1::ABSOLUTE; }

void ToProto(const std::vector<std::string>& part_names, const VariantProvenance& provenance,
             v1::ClipProvenance* out) {
  out->set_parent(provenance.parent);
  out->set_generator(provenance.generator);
  if (provenance.part >= 0 && provenance.part < static_cast<int>(part_names.size())) {
    out->set_part(part_names[provenance.part]);
  }
  out->set_seed(provenance.seed);
}

// One entry per clip now in the session: what the ledger recorded and what the sampler makes
// of it (`probabilities` = session.adaptive_sampler.Weights(), the floor applied).
void FillClipSamplingStates(const SimulationSession& session, const std::vector<double>& probabilities,
                            google::protobuf::RepeatedPtrField<v1::ClipSamplingState>* out)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(session.mutex) {
  const std::vector<double>& weights = session.adaptive_sampler.raw_weights();
  const SessionMotionSet& motion_set = session.motion_set;
  for (int c = 0; c < motion_set.size(); ++c) {
    const ClipFailureRecord& record = session.ledger.clips()[c];
    const SessionClipInfo& info = motion_set.info(c);
    v1::ClipSamplingState* clip = out->Add();
    clip->set_clip(info.name);
    clip->set_clip_id(info.id);
    if (info.provenance.has_value()) ToProto(motion_set.part_names(), *info.provenance, clip->mutable_provenance());
    clip->set_weight(weights[c]);
    clip->set_probability(probabilities[c]);
    clip->set_failures(record.failures);
    clip->set_successes(record.successes);
    clip->set_last_failed_frame(record.last_failed_frame);
    for (double e : record.mean_part_errors) clip->add_mean_part_errors(static_cast<float>(e));
  }
}

void FillGenerationStats(const SimulationSession& session, v1::GenerationStats* out)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(session.mutex) {
  const GenerationCounters& counters = session.generation;
  out->set_enabled(session.motion_set.options().enabled);
  out->set_live_generated_clips(session.motion_set.live_generated());
  out->set_requests(counters.requests);
  out->set_generated(counters.generated);
  out->set_rejected(counters.rejected);
  for (const auto& [check, count] : counters.rejected_by_check) (*out->mutable_rejected_by_check())[check] = count;
  out->set_evicted(counters.evicted);
  out->set_generator_errors(counters.generator_errors);
  out->set_last_generator_error(counters.last_generator_error);
  out->set_builtin_fallbacks(counters.builtin_fallbacks);
  out->set_dropped_requests(counters.dropped_requests);
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

}  // namespace

absl::StatusOr<std::unique_ptr<SimulationService>> SimulationService::Create(
    const ServiceOptions& options, std::shared_ptr<const MotionLibrary> motions) {
  if (motions != nullptr && motions->size() > options.max_library_clips) {
    return absl::InvalidArgumentError(absl::StrCat("--max_library_clips: ", options.max_library_clips,
                                                   ", but the library already holds ", motions->size(), " clips"));
  }
  if (motions == nullptr || motions->size() == 0) return absl::InvalidArgumentError("motions: the library is empty");
  if (absl::Status status = ValidateSamplingParameters(options.sampling_floor, kDefaultSamplingDecay); !status.ok()) {
    return status;
  }
  if (absl::Status status = ValidateGenerationOptions(options.generation); !status.ok()) return status;
  if (!(options.generator_timeout > absl::ZeroDuration())) {
    return absl::InvalidArgumentError("--generator_timeout_ms: must be > 0");
  }
  std::unique_ptr<SimulationService> service(new SimulationService(options, motions));
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return spec.status();
  service->skeleton_ = std::make_unique<HumanoidSpec>(*spec);
  auto humanoid = HumanoidModel::Create(*spec, options.physics);
  if (!humanoid.ok()) return humanoid.status();
  service->humanoid_ = *std::move(humanoid);
  auto layouts = PartLayoutCatalog::LoadDefault(*spec);
  if (!layouts.ok()) return layouts.status();
  service->layouts_ = std::make_unique<PartLayoutCatalog>(*std::move(layouts));
  std::unique_ptr<ExternalMotionGenerator> external;
  if (!options.generator_address.empty()) {
    external = std::make_unique<ExternalMotionGenerator>(options.generator_address, options.generator_timeout);
  }
  service->generation_worker_ =
      std::make_unique<GenerationWorker>(service->skeleton_.get(), std::move(external), options.plausibility,
                                         options.generated_clip_dir, options.max_saved_generated_clips);
  return service;
}

grpc::Status SimulationService::CheckAuth(const grpc::ServerContext* context) const {
  if (options_.auth_token.empty()) return grpc::Status::OK;
  const auto& metadata = context->client_metadata();
  auto it = metadata.find("authorization");
  if (it == metadata.end()) return Error(grpc::StatusCode::UNAUTHENTICATED, "authorization: missing bearer token");
  const std::string value(it->second.data(), it->second.size());
  if (!SameSecret(value, "Bearer " + options_.auth_token)) {
    return Error(grpc::StatusCode::UNAUTHENTICATED, "authorization: wrong bearer token");
  }
  return grpc::Status::OK;
}

absl::StatusOr<PartLayout> SimulationService::Layout(const std::string& name) const {
  return FindLayout(*layouts_, name);
}

grpc::Status SimulationService::Describe(grpc::ServerContext* context, const v1::DescribeRequest* request,
                                         v1::EnvSpec* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  auto layout = Layout(request->part_layout());
  if (!layout.ok()) return ToGrpcStatus(layout.status());
  ToProto(MakeEnvSpec(*humanoid_, *layout), *humanoid_, response);
  for (const std::string& name : layouts_->Names()) response->add_part_layouts(name);
  for (const std::string& name : ActionModeNames()) response->add_action_modes(name);
  for (const std::string& name : TerminationBodiesNames()) response->add_termination_bodies(name);
  response->set_num_motions(motions_.Snapshot()->size());
  return grpc::Status::OK;
}

grpc::Status SimulationService::Simulate(grpc::ServerContext* context,
                                         grpc::ServerReaderWriter<v1::SimulateResponse, v1::SimulateRequest>* stream) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  v1::SimulateRequest request;
  if (!stream->Read(&request)) return Error(grpc::StatusCode::INVALID_ARGUMENT, "config: the stream ended before it");
  if (!request.has_config()) {
    return Error(grpc::StatusCode::INVALID_ARGUMENT, "config: the first message must carry the session config");
  }
  const v1::SessionConfig& config = request.config();
  auto settings = ParseSessionConfig(config, options_.max_envs_per_session, options_.max_library_clips, *layouts_);
  if (!settings.ok()) return ToGrpcStatus(settings.status());
  const int amp_frames = settings->amp_frames;

  std::shared_ptr<const MotionLibrary> motions = motions_.Snapshot();
  if (config.motions_size() > 0) {
    auto subset = motions->Subset({config.motions().begin(), config.motions().end()});
    if (!subset.ok()) return ToGrpcStatus(subset.status());
    motions = std::make_shared<const MotionLibrary>(*std::move(subset));
  }
  auto session_id = registry_.Reserve();
  if (!session_id.ok()) return ToGrpcStatus(session_id.status());

  EnvBatchConfig batch_config;
  batch_config.num_envs = settings->num_envs;
  batch_config.num_threads = options_.threads_per_session;
  batch_config.seed = settings->seed;
  batch_config.env = settings->env;
  auto batch = EnvBatch::Create(batch_config, humanoid_, settings->layout, motions);
  if (!batch.ok()) {
    registry_.Release();
    return ToGrpcStatus(batch.status());
  }
  auto session = std::make_shared<SimulationSession>(*session_id, context->peer(), *std::move(batch),
                                                     options_.sampling, options_.sampling_floor, options_.generation,
                                                     config.seed());
  registry_.Register(session);
  EnvBatch& envs = *session->batch;
  LogLine("session %s opened by %s: %d envs, %d clips, layout %s", session->id, session->peer, envs.num_envs(),
          motions->size(), settings->layout.name);

  // The same messages are reused for every step so that their buffers keep their capacity.
  v1::SimulateResponse response;
  envs.Reset();
  {
    v1::SessionOpened* opened = response.mutable_opened();
    opened->set_session_id(session->id);
    ToProto(envs.spec(), *humanoid_, opened->mutable_spec());
    opened->mutable_spec()->set_num_motions(motions->size());
    for (const std::string& name : session->clip_names) opened->add_clip_names(name);
    FillStepResult(envs, 0, amp_frames, opened->mutable_initial());
  }
  grpc::Status result = grpc::Status::OK;
  std::vector<float> actions;
  std::vector<double> clip_weights;  // swapped with the session's pending weights, so reused
  std::optional<PendingMotionSet> motion_set;
  const std::vector<std::string> part_names = envs.spec().layout.PartNames();
  const int64_t n = envs.num_envs(), action_size = envs.spec().action_size;
  const char* ending = "client closed the stream";
  if (!stream->Write(response)) {
    ending = "client went away";
  } else {
    response.mutable_step();  // switch the oneof once; its tensors are then reused
    while (stream->Read(&request)) {
      if (!request.has_actions()) {
        result = Error(grpc::StatusCode::INVALID_ARGUMENT, "actions: every message after the config carries actions");
        break;
      }
      if (absl::Status status = ReadFloatTensor(request.actions(), "actions", {n, action_size}, &actions); !status.ok()) {
        result = ToGrpcStatus(status);
        break;
      }
      if (request.termination_distance() != 0 &&
          request.termination_distance() != envs.env_config().termination_distance) {
        if (absl::Status status = envs.SetTerminationDistance(request.termination_distance()); !status.ok()) {
          result = ToGrpcStatus(status);
          break;
        }
      }
      // New sampling weights (ReportFailures) and clips (generation rounds) take effect here,
      // between two steps: this thread alone steps the batch, so no env is drawing a clip meanwhile.
      response.mutable_step()->clear_motion_set_update();
      if (session->TakePending(&clip_weights, &motion_set)) {
        const absl::Status status =
            motion_set.has_value()
                ? envs.SetMotions(motion_set->library, motion_set->clip_ids, motion_set->reference_amp, clip_weights)
                : envs.SetClipWeights(clip_weights);
        if (!status.ok()) {
          result = Error(grpc::StatusCode::INTERNAL, absl::StrCat("sampler: ", status.message()));
          break;
        }
        if (motion_set.has_value()) ToProto(part_names, *motion_set, response.mutable_step()->mutable_motion_set_update());
      }
      if (absl::Status status = envs.Step(actions); !status.ok()) {
        result = ToGrpcStatus(status);
        break;
      }
      int64_t episodes = 0;
      for (uint8_t done : envs.buffers().done) episodes += done;
      const int64_t physics_resets = envs.physics_resets() - session->physics_resets;
      session->physics_resets += physics_resets;
      session->episodes += episodes;
      registry_.AddSteps(n, episodes, physics_resets);
      FillStepResult(envs, ++session->steps, amp_frames, response.mutable_step());
      if (!stream->Write(response)) {
        ending = "client went away";
        break;
      }
    }
  }
  if (!result.ok()) ending = "error";
  const double seconds = absl::ToDoubleSeconds(absl::Now() - session->opened);
  LogLine("session %s closed (%s%s%s): %lld steps x %d envs in %.1f s, %.0f env steps/s, %lld episodes, "
          "%lld physics resets, %lld failure reports",
          session->id, ending, result.ok() ? "" : ": ", result.error_message(), static_cast<long long>(session->steps),
          envs.num_envs(), seconds, seconds > 0 ? session->steps * n / seconds : 0.0,
          static_cast<long long>(session->episodes), static_cast<long long>(session->physics_resets),
          static_cast<long long>(session->failure_reports));
  registry_.Close(session->id);
  return result;
}

grpc::Status SimulationService::ReportFailures(grpc::ServerContext* context, const v1::ReportFailuresRequest* request,
                                               v1::SamplerState* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  std::shared_ptr<SimulationSession> session = registry_.Find(request->session_id());
  if (session == nullptr) {
    return Error(grpc::StatusCode::NOT_FOUND, absl::StrCat("session_id: no open session '", ShownValue(request->session_id()), "'"));
  }
  std::vector<NamedClipReport> reports;
  reports.reserve(request->failures_size());
  for (const v1::ClipFailure& failure : request->failures()) {
    reports.push_back(NamedClipReport{failure.clip(), failure.frame(),
                                      {failure.part_errors().begin(), failure.part_errors().end()},
                                      failure.terminated()});
  }
  if (!request->discriminator().empty()) {
    auto scorer = DiscriminatorScorer::LoadBytes(request->discriminator(), session->batch->spec().amp_obs_size);
    if (!scorer.ok()) return ToGrpcStatus(scorer.status());
    session->SetDiscriminator(*std::move(scorer));
  }
  auto rounds = session->RecordReports(reports);
  if (!rounds.ok()) return ToGrpcStatus(rounds.status());
  generation_worker_->Enqueue(session, *std::move(rounds));
  session->failure_reports += request->failures_size();
  registry_.AddFailureReports(request->failures_size());
  response->set_session_id(session->id);
  absl::MutexLock lock(&session->mutex);
  response->set_reports(session->ledger.reports());
  FillClipSamplingStates(*session, session->adaptive_sampler.Weights(), response->mutable_clips());
  return grpc::Status::OK;
}

grpc::Status SimulationService::SampleReferenceAmp(grpc::ServerContext* context,
                                                   const v1::SampleReferenceAmpRequest* request,
                                                   v1::SampleReferenceAmpResponse* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  std::shared_ptr<SimulationSession> session = registry_.Find(request->session_id());
  if (session == nullptr) {
    return Error(grpc::StatusCode::NOT_FOUND, absl::StrCat("session_id: no open session '", ShownValue(request->session_id()), "'"));
  }
  if (request->num_samples() < 1 || request->num_samples() > kMaxReferenceAmpSamples) {
    return Error(grpc::StatusCode::INVALID_ARGUMENT,
                 absl::StrCat("num_samples: ", request->num_samples(), " outside [1, ", kMaxReferenceAmpSamples, "]"));
  }
  const std::shared_ptr<const ReferenceAmpFrames> reference_frames = session->reference_amp();
  const ReferenceAmpFrames& reference = *reference_frames;
  const int64_t n = request->num_samples(), width = int64_t{kAmpHistory} * reference.per_frame();
  // The response must fit the message limit (4 bytes per float, plus a little framing).
  const int64_t fit = (options_.max_response_bytes - 4096) / (width * int64_t{sizeof(float)});
  if (n > fit) {
    return Error(grpc::StatusCode::INVALID_ARGUMENT,
                 absl::StrCat("num_samples: ", n, " samples of ", width, " floats exceed the server's message limit of ",
                              options_.max_response_bytes >> 20, " MiB (--max_message_mb); ask for at most ",
                              std::max<int64_t>(fit, 0), " per request"));
  }
  std::vector<float> samples(static_cast<size_t>(n * width));
  std::mt19937_64 rng(request->seed());
  reference.Sample(static_cast<int>(n), rng, samples.data());
  SetFloatTensor({n, width}, samples.data(), response->mutable_amp_obs());
  return grpc::Status::OK;
}

grpc::Status SimulationService::Rollout(grpc::ServerContext* context, const v1::RolloutRequest* request,
                                        grpc::ServerWriter<v1::RolloutResponse>* writer) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> policy;
  if (request->has_checkpoint_path()) {
    // Only files in the operator's --checkpoint_dir directories, and no larger than an upload.
    auto bytes = ReadConfinedFile(options_.checkpoint_dirs, request->checkpoint_path(), options_.max_upload_bytes,
                                  "checkpoint_path");
    if (!bytes.ok()) return ToGrpcStatus(bytes.status());
    policy = PolicyCheckpoint::LoadBytes(*bytes);
  } else if (request->has_checkpoint_bytes()) {
    policy = PolicyCheckpoint::LoadBytes(request->checkpoint_bytes());
  } else {
    return Error(grpc::StatusCode::INVALID_ARGUMENT, "checkpoint: set checkpoint_path or checkpoint_bytes");
  }
  if (!policy.ok()) return ToGrpcStatus(policy.status());
  auto layout = Layout((*policy)->spec().part_layout);
  if (!layout.ok()) {
    return Error(grpc::StatusCode::FAILED_PRECONDITION,
                 absl::StrCat("checkpoint: trained with layout '", (*policy)->spec().part_layout,
                              "' that this server does not offer"));
  }
  const EnvSpec spec = MakeEnvSpec(*humanoid_, *layout);
  if (absl::Status status = CheckPolicyFitsEnv((*policy)->spec(), spec); !status.ok()) return ToGrpcStatus(status);
  const ActionMapping& trained_mapping = (*policy)->spec().action;
  if (!v1::ActionMode_IsValid(request->action_mode())) {
    return Error(grpc::StatusCode::INVALID_ARGUMENT,
                 absl::StrCat("action_mode: unknown value ", static_cast<int>(request->action_mode())));
  }
  if (request->action_mode() != v1::ACTION_MODE_UNSPECIFIED && request->action_mode() != ToProto(trained_mapping.mode)) {
    return Error(grpc::StatusCode::FAILED_PRECONDITION,
                 absl::StrCat("action_mode: the checkpoint was trained in ", ActionModeName(trained_mapping.mode),
                              " mode; it cannot run in ", v1::ActionMode_Name(request->action_mode())));
  }
  if (request->max_steps_per_clip() < 0) return Error(grpc::StatusCode::INVALID_ARGUMENT, "max_steps_per_clip: < 0");

  std::shared_ptr<const MotionLibrary> motions = motions_.Snapshot();
  std::vector<int> clip_ids;
  for (int c = 0; c < request->clips_size(); ++c) {
    const int id = motions->Find(request->clips(c));
    if (id < 0) return Error(grpc::StatusCode::NOT_FOUND, absl::StrCat("clips[", c, "]: unknown clip '", ShownValue(request->clips(c)), "'"));
    clip_ids.push_back(id);
  }
  if (clip_ids.empty()) {
    for (int c = 0; c < motions->size(); ++c) clip_ids.push_back(c);
  }
  auto termination = ToTermination(request->termination(), v1::EVALUATION);
  if (!termination.ok()) return ToGrpcStatus(termination.status());
  auto distance = ToTerminationDistance(request->termination_distance(), *termination);
  if (!distance.ok()) return ToGrpcStatus(distance.status());
  RolloutOptions options;
  options.termination = *termination;
  options.termination_distance = *distance;
  options.action = trained_mapping;
  options.max_steps_per_clip = request->max_steps_per_clip();
  options.num_threads = options_.threads_per_session;
  options.physics = options_.physics;

  bool client_gone = false;
  v1::RolloutResponse frame_message;
  RolloutFrameCallback on_frame = nullptr;
  if (request->stream_frames()) {
    on_frame = [&](int clip_index, int frame, const std::vector<Vec3>& sim, const std::vector<Vec3>& ref) {
      if (client_gone) return;
      v1::RolloutFrame* out = frame_message.mutable_frame();
      out->set_clip(motions->clip(clip_ids[clip_index]).name);
      out->set_frame(frame);
      std::vector<float> sim_flat, ref_flat;
      for (size_t b = 0; b < sim.size(); ++b) {
        for (int k = 0; k < 3; ++k) {
          sim_flat.push_back(static_cast<float>(sim[b][k]));
          ref_flat.push_back(static_cast<float>(ref[b][k]));
        }
      }
      const int64_t bodies = static_cast<int64_t>(sim.size());
      SetFloatTensor({bodies, 3}, sim_flat.data(), out->mutable_sim_body_pos());
      SetFloatTensor({bodies, 3}, ref_flat.data(), out->mutable_ref_body_pos());
      client_gone = !writer->Write(frame_message);
    };
  }
  PolicyCheckpoint* checkpoint = policy->get();
  auto metrics = RunRollout(
      humanoid_, *layout, motions, clip_ids,
      [&](const float* obs, int n, float* actions) -> absl::Status {
        if (context->IsCancelled() || client_gone) return absl::CancelledError("rollout: the client went away");
        return checkpoint->Act(obs, n, actions);
      },
      options, on_frame);
  if (!metrics.ok()) return ToGrpcStatus(metrics.status());
  int successes = 0;
  for (const ClipRolloutMetrics& clip : *metrics) {
    v1::RolloutResponse message;
    ToProto(clip, message.mutable_metrics());
    successes += clip.success;
    if (!writer->Write(message)) break;
  }
  LogLine("rollout by %s: %d clips, %d succeeded", context->peer(), static_cast<int>(metrics->size()), successes);
  return grpc::Status::OK;
}

grpc::Status SimulationService::ListMotions(grpc::ServerContext* context, const v1::ListMotionsRequest* request,
                                            v1::ListMotionsResponse* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  std::shared_ptr<const MotionLibrary> motions = motions_.Snapshot();
  for (int c = 0; c < motions->size(); ++c) ToProto(motions->clip(c), response->add_motions());
  return grpc::Status::OK;
}

grpc::Status SimulationService::AddMotions(grpc::ServerContext* context, const v1::AddMotionsRequest* request,
                                           v1::AddMotionsResponse* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  if (request->uploads_size() == 0) return Error(grpc::StatusCode::INVALID_ARGUMENT, "uploads: none");
  int64_t total = 0;
  for (const v1::MotionUpload& upload : request->uploads()) total += upload.data().size();
  if (total > options_.max_upload_bytes) {
    return Error(grpc::StatusCode::RESOURCE_EXHAUSTED, absl::StrCat("uploads: ", total, " bytes exceed --max_upload_mb (",
                                                                    options_.max_upload_bytes, " bytes)"));
  }
  // Importers read files: each upload goes through a private temporary directory.
  std::error_code error;
  const std::filesystem::path dir = std::filesystem::temp_directory_path(error) /
                                    absl::StrCat("modskill-upload-", ::getpid(), "-", absl::ToUnixNanos(absl::Now()));
  std::filesystem::create_directories(dir, error);
  if (error) return Error(grpc::StatusCode::INTERNAL, absl::StrCat("uploads: cannot create a temporary directory: ", error.message()));
  std::vector<MotionClip> clips;
  grpc::Status result = grpc::Status::OK;
  for (int u = 0; u < request->uploads_size() && result.ok(); ++u) {
    const v1::MotionUpload& upload = request->uploads(u);
    const std::string file_name = std::filesystem::path(upload.file_name()).filename().string();
    if (file_name.empty() || file_name == "." || file_name == "..") {
      result = Error(grpc::StatusCode::INVALID_ARGUMENT, absl::StrCat("uploads[", u, "].file_name: empty"));
      break;
    }
    const std::string path = (dir / file_name).string();
    {
      std::ofstream out(path, std::ios::binary);
      out.write(upload.data().data(), static_cast<std::streamsize>(upload.data().size()));
    }
    ImportOptions import;
    import.name = upload.name();
    import.label = upload.label();
    auto clip = ImportMotionFile(path, *skeleton_, import);
    if (!clip.ok()) {
      // The message names the temporary path; name the upload instead.
      std::string message(clip.status().message());
      const size_t at = message.find(path);
      if (at != std::string::npos) message.replace(at, path.size(), file_name);
      // Whatever the importer saw (truncation, bad fields), the client sent bad data.
      result = Error(grpc::StatusCode::INVALID_ARGUMENT, absl::StrCat("uploads[", u, "]: ", message));
      break;
    }
    if (clip->source.empty() || clip->source == file_name) clip->source = absl::StrCat("upload:", file_name);
    clips.push_back(*std::move(clip));
  }
  std::filesystem::remove_all(dir, error);
  if (!result.ok()) return result;
  std::vector<MotionClip> added = clips;
  if (absl::Status status = motions_.Add(std::move(clips), options_.max_library_clips); !status.ok()) {
    return ToGrpcStatus(status);
  }
  for (const MotionClip& clip : added) ToProto(clip, response->add_added());
  LogLine("%d clips added by %s", static_cast<int>(added.size()), context->peer());
  return grpc::Status::OK;
}

grpc::Status SimulationService::GetStats(grpc::ServerContext* context, const v1::GetStatsRequest* request,
                                         v1::ServerStats* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  ServerTotals totals = registry_.Totals();
  response->set_active_sessions(totals.active_sessions);
  response->set_sessions_opened(totals.sessions_opened);
  response->set_env_steps(totals.env_steps);
  response->set_env_steps_per_second(totals.env_steps_per_second);
  response->set_episodes(totals.episodes);
  response->set_physics_resets(totals.physics_resets);
  response->set_failure_reports(totals.failure_reports);
  response->set_uptime_seconds(totals.uptime_seconds);
  response->set_num_motions(motions_.Snapshot()->size());
  const absl::Time now = absl::Now();
  for (const auto& session : totals.sessions) {
    v1::SessionStats* stats = response->add_sessions();
    stats->set_session_id(session->id);
    stats->set_peer(session->peer);
    stats->set_num_envs(session->batch->num_envs());
    stats->set_steps(session->steps);
    const double seconds = absl::ToDoubleSeconds(now - session->opened);
    stats->set_steps_per_second(seconds > 0 ? session->steps * session->batch->num_envs() / seconds : 0);
    stats->set_episodes(session->episodes);
    stats->set_physics_resets(session->physics_resets);
    stats->set_failure_reports(session->failure_reports);
    absl::MutexLock lock(&session->mutex);
    FillClipSamplingStates(*session, session->adaptive_sampler.Weights(), stats->mutable_clips());
    FillGenerationStats(*session, stats->mutable_generation());
  }
  return grpc::Status::OK;
}

}  // namespace modskill
