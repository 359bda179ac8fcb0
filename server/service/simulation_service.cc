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
#include "common/wire/policy_enums.h"
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
    clip->set_reported_steps(record.steps);
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

grpc::Status SimulationService::ReportFailures(grpc::ServerContext* context, const v1::ReportFailuresRequest* request,
                                               v1::SamplerState* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  std::shared_ptr<SimulationSession> session = registry_.Find(request->session_id());
  if (session == nullptr) {
    return Error(grpc::StatusCode::NOT_FOUND, absl::StrCat("session_id: no open session '", ShownValue(request->session_id()), "'"));
  }
  if (!session->batch->spec().family.empty()) {
    // A family keeps its one clip: there is nothing to resample or vary.
    return Error(grpc::StatusCode::FAILED_PRECONDITION,
                 absl::StrCat("session_id: '", session->id, "' is a family session, which takes no failure reports"));
  }
  std::vector<NamedClipReport> reports;
  reports.reserve(request->failures_size());
  for (const v1::ClipFailure& failure : request->failures()) {
    reports.push_back(NamedClipReport{failure.clip(), failure.frame(),
                                      {failure.part_errors().begin(), failure.part_errors().end()},
                                      failure.terminated(), failure.steps()});
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
