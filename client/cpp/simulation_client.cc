#include "client/cpp/simulation_client.h"


#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/cpp/step_result_check.h"
#include "common/atomic_file.h"
#include "common/grpc_status.h"

namespace modskill {

absl::StatusOr<std::string> ReadTokenFile(const std::string& path) {
  auto text = ReadFileToString(path, 4096);
  if (!text.ok()) return text.status();
  std::string token(absl::StripAsciiWhitespace(*text));
  if (token.empty()) return absl::InvalidArgumentError(absl::StrCat(path, ": empty token file"));
  return token;
}

absl::StatusOr<std::unique_ptr<SimulationClient>> SimulationClient::Connect(const ClientOptions& options) {
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  grpc::ChannelArguments arguments;
  if (!options.tls_ca_file.empty()) {
    auto roots = ReadFileToString(options.tls_ca_file, 1 << 20);
    if (!roots.ok()) return absl::InvalidArgumentError(absl::StrCat("tls_ca: ", roots.status().message()));
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = *roots;
    credentials = grpc::SslCredentials(ssl);
    if (!options.tls_server_name.empty()) arguments.SetSslTargetNameOverride(options.tls_server_name);
  }
  arguments.SetMaxReceiveMessageSize(static_cast<int>(std::min<int64_t>(options.max_message_bytes, INT32_MAX)));
  arguments.SetMaxSendMessageSize(static_cast<int>(std::min<int64_t>(options.max_message_bytes, INT32_MAX)));
  // Large step results flow without waiting for HTTP/2 window updates.
  arguments.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 64 << 20);
  // A server behind a cut link or a dead host sends nothing, not even a reset: without pings a
  // stream read would wait for TCP's own timeout (~15 minutes). The server permits a ping a second.
  arguments.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, static_cast<int>(absl::ToInt64Milliseconds(options.keepalive_time)));
  arguments.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, static_cast<int>(absl::ToInt64Milliseconds(options.keepalive_timeout)));
  arguments.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  arguments.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  std::unique_ptr<SimulationClient> client(new SimulationClient(options));
  client->channel_ = grpc::CreateCustomChannel(options.server, credentials, arguments);
  if (!client->channel_->WaitForConnected(absl::ToChronoTime(absl::Now() + options.connect_timeout))) {
    return absl::UnavailableError(absl::StrCat("server ", options.server, ": no answer within ",
                                               absl::FormatDuration(options.connect_timeout)));
  }
  client->stub_ = v1::Simulation::NewStub(client->channel_);
  return client;
}

void SimulationClient::Prepare(grpc::ClientContext* context) const {
  if (!options_.token.empty()) context->AddMetadata("authorization", "Bearer " + options_.token);
}

absl::Status SimulationClient::FromGrpc(const grpc::Status& status, const std::string& rpc) const {
  return FromGrpcStatus(status, absl::StrCat(options_.server, " ", rpc));
}

absl::StatusOr<v1::EnvSpec> SimulationClient::Describe(const std::string& part_layout) {
  grpc::ClientContext context;
  Prepare(&context);
  v1::DescribeRequest request;
  request.set_part_layout(part_layout);
  v1::EnvSpec spec;
  if (auto status = FromGrpc(stub_->Describe(&context, request, &spec), "Describe"); !status.ok()) return status;
  return spec;
}

absl::StatusOr<v1::ListMotionsResponse> SimulationClient::ListMotions() {
  grpc::ClientContext context;
  Prepare(&context);
  v1::ListMotionsResponse response;
  if (auto status = FromGrpc(stub_->ListMotions(&context, {}, &response), "ListMotions"); !status.ok()) return status;
  return response;
}

absl::StatusOr<v1::ServerStats> SimulationClient::GetStats() {
  grpc::ClientContext context;
  Prepare(&context);
  v1::ServerStats response;
  if (auto status = FromGrpc(stub_->GetStats(&context, {}, &response), "GetStats"); !status.ok()) return status;
  return response;
}

absl::StatusOr<v1::QueryFamilyResponse> SimulationClient::QueryFamily(const v1::QueryFamilyRequest& request) {
  grpc::ClientContext context;
  Prepare(&context);
  v1::QueryFamilyResponse response;
  if (auto status = FromGrpc(stub_->QueryFamily(&context, request, &response), "QueryFamily"); !status.ok()) return status;
  return response;
}

absl::StatusOr<v1::AddMotionsResponse> SimulationClient::AddMotionFiles(const std::vector<std::string>& paths) {
  v1::AddMotionsRequest request;
  for (const std::string& path : paths) {
    auto bytes = ReadFileToString(path, size_t{1} << 30);
    if (!bytes.ok()) return bytes.status();
    v1::MotionUpload* upload = request.add_uploads();
    upload->set_file_name(path.substr(path.find_last_of('/') + 1));
    upload->set_data(*std::move(bytes));
  }
  return AddMotions(request);
}

absl::StatusOr<v1::AddMotionsResponse> SimulationClient::AddMotions(const v1::AddMotionsRequest& request) {
  grpc::ClientContext context;
  Prepare(&context);
  v1::AddMotionsResponse response;
  if (auto status = FromGrpc(stub_->AddMotions(&context, request, &response), "AddMotions"); !status.ok()) return status;
  return response;
}

absl::StatusOr<v1::SamplerState> SimulationClient::ReportFailures(const v1::ReportFailuresRequest& request) {
  grpc::ClientContext context;
  Prepare(&context);
  v1::SamplerState response;
  if (auto status = FromGrpc(stub_->ReportFailures(&context, request, &response), "ReportFailures"); !status.ok()) {
    return status;
  }
  return response;
}

absl::StatusOr<v1::SampleReferenceAmpResponse> SimulationClient::SampleReferenceAmp(
    const v1::SampleReferenceAmpRequest& request) {
  grpc::ClientContext context;
  Prepare(&context);
  v1::SampleReferenceAmpResponse response;
  if (auto status = FromGrpc(stub_->SampleReferenceAmp(&context, request, &response), "SampleReferenceAmp");
      !status.ok()) {
    return status;
  }
  return response;
}

absl::StatusOr<std::vector<v1::ClipMetrics>> SimulationClient::Rollout(
    const v1::RolloutRequest& request, const std::function<void(const v1::RolloutFrame&)>& on_frame) {
  grpc::ClientContext context;
  Prepare(&context);
  std::unique_ptr<grpc::ClientReader<v1::RolloutResponse>> reader = stub_->Rollout(&context, request);
  std::vector<v1::ClipMetrics> metrics;
  v1::RolloutResponse response;
  while (reader->Read(&response)) {
    if (response.has_metrics()) metrics.push_back(response.metrics());
    if (response.has_frame() && on_frame) on_frame(response.frame());
  }
  if (auto status = FromGrpc(reader->Finish(), "Rollout"); !status.ok()) return status;
  return metrics;
}

absl::StatusOr<std::unique_ptr<SimulationStream>> SimulationClient::OpenSession(const v1::SessionConfig& config) {
  std::unique_ptr<SimulationStream> stream(new SimulationStream());
  stream->server_ = options_.server;
  Prepare(&stream->context_);
  stream->stream_ = stub_->Simulate(&stream->context_);
  v1::SimulateRequest request;
  *request.mutable_config() = config;
  if (!stream->stream_->Write(request)) return stream->Fail("Simulate");
  v1::SimulateResponse response;
  if (!stream->stream_->Read(&response)) return stream->Fail("Simulate");
  if (!response.has_opened()) return absl::InternalError(absl::StrCat(options_.server, " Simulate: no SessionOpened reply"));
  stream->opened_ = std::move(*response.mutable_opened());
  stream->clip_names_.assign(stream->opened_.clip_names().begin(), stream->opened_.clip_names().end());
  stream->live_clips_ = stream->opened_.clip_names_size();
  stream->num_envs_ = config.num_envs();
  stream->action_size_ = stream->opened_.spec().action_size();
  if (absl::Status status = CheckStepResult(stream->opened_.initial(), stream->num_envs_, stream->spec()); !status.ok()) {
    return absl::Status(status.code(), absl::StrCat(options_.server, " Simulate: initial ", status.message()));
  }
  return stream;
}

SimulationStream::~SimulationStream() {
  if (stream_ != nullptr && !closed_) {
    context_.TryCancel();
    stream_->Finish().ok();
  }
}

absl::Status SimulationStream::Fail(const std::string& what) {
  closed_ = true;
  const grpc::Status status = stream_->Finish();
  if (status.ok()) return absl::UnavailableError(absl::StrCat(server_, " ", what, ": the stream ended"));
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                      absl::StrCat(server_, " ", what, ": ", status.error_message()));
}

absl::Status SimulationStream::SendActions(const float* actions) {
  if (closed_) return absl::FailedPreconditionError("session: already closed");
  v1::Tensor* tensor = request_.mutable_actions();
  tensor->clear_shape();
  tensor->add_shape(num_envs_);
  tensor->add_shape(action_size_);
  tensor->set_dtype(v1::FLOAT32);
  tensor->mutable_data()->assign(reinterpret_cast<const char*>(actions),
                                 sizeof(float) * static_cast<size_t>(num_envs_) * action_size_);
  last_request_bytes_ = request_.ByteSizeLong();
  const bool written = stream_->Write(request_);
  request_.clear_family_params();  // sent once; the server keeps them
  if (!written) return Fail("Simulate");
  return absl::OkStatus();
}

void SimulationStream::SetFamilyParameters(const std::vector<float>& rows) {
  v1::Tensor* tensor = request_.mutable_family_params();
  tensor->clear_shape();
  tensor->add_shape(num_envs_);
  tensor->add_shape(spec().family_size());
  tensor->set_dtype(v1::FLOAT32);
  tensor->mutable_data()->assign(reinterpret_cast<const char*>(rows.data()), sizeof(float) * rows.size());
}

absl::Status SimulationStream::ReceiveResult() {
  if (closed_) return absl::FailedPreconditionError("session: already closed");
  if (!stream_->Read(&response_)) return Fail("Simulate");
  if (!response_.has_step()) return absl::InternalError(absl::StrCat(server_, " Simulate: expected a step result"));
  if (absl::Status status = CheckStepResult(response_.step(), num_envs_, spec()); !status.ok()) {
    return absl::Status(status.code(), absl::StrCat(server_, " Simulate: ", status.message()));
  }
  last_response_bytes_ = response_.ByteSizeLong();
  if (response_.step().has_motion_set_update()) {
    const v1::MotionSetUpdate& update = response_.step().motion_set_update();
    for (const v1::SessionClip& clip : update.added()) {
      if (clip.clip_id() < 0 || clip.clip_id() > (1 << 24)) continue;  // not an id a server hands out
      if (clip.clip_id() >= static_cast<int>(clip_names_.size())) clip_names_.resize(clip.clip_id() + 1);
      clip_names_[clip.clip_id()] = clip.name();
    }
    live_clips_ += update.added_size() - update.removed_clip_ids_size();
  }
  return absl::OkStatus();
}

const std::string& SimulationStream::clip_name(int id) const {
  static const std::string kUnknown;
  return id >= 0 && id < static_cast<int>(clip_names_.size()) ? clip_names_[id] : kUnknown;
}

absl::Status SimulationStream::Step(const float* actions) {
  if (auto status = SendActions(actions); !status.ok()) return status;
  return ReceiveResult();
}

absl::Status SimulationStream::Close() {
  if (closed_) return absl::OkStatus();
  closed_ = true;
  stream_->WritesDone();
  const grpc::Status status = stream_->Finish();
  if (status.ok()) return absl::OkStatus();
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                      absl::StrCat(server_, " Simulate: ", status.error_message()));
}

}  // namespace modskill
