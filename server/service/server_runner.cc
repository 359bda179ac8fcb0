#include "server/service/server_runner.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/atomic_file.h"

namespace modskill {

void RunningServer::Shutdown(absl::Duration grace) {
  server_->Shutdown(absl::ToChronoTime(absl::Now() + grace));
}

absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options,
                                                           std::shared_ptr<const MotionLibrary> motions) {
  if (options.port < 0 || options.port > 65535) {
    return absl::InvalidArgumentError(absl::StrCat("port: ", options.port, " outside [0, 65535]"));
  }
  ServiceOptions service_options = options.service;
  // Responses that would not fit the message limit are refused up front, naming the field.
  service_options.max_response_bytes = options.max_message_bytes;
  auto service = SimulationService::Create(service_options, std::move(motions));
  if (!service.ok()) return service.status();
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (!options.tls_cert_file.empty() || !options.tls_key_file.empty()) {
    if (options.tls_cert_file.empty() || options.tls_key_file.empty()) {
      return absl::InvalidArgumentError("tls_cert/tls_key: set both or neither");
    }
    auto cert = ReadFileToString(options.tls_cert_file, 1 << 20);
    if (!cert.ok()) return absl::InvalidArgumentError(absl::StrCat("tls_cert: ", cert.status().message()));
    auto key = ReadFileToString(options.tls_key_file, 1 << 20);
    if (!key.ok()) return absl::InvalidArgumentError(absl::StrCat("tls_key: ", key.status().message()));
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({*key, *cert});
    credentials = grpc::SslServerCredentials(ssl);
  }
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  auto running = std::unique_ptr<RunningServer>(new RunningServer());
  const std::string address = absl::StrCat(options.bind.find(':') != std::string::npos ? "[" + options.bind + "]" : options.bind,
                                           ":", options.port);
  builder.AddListeningPort(address, credentials, &running->port_);
  builder.SetMaxReceiveMessageSize(static_cast<int>(std::min<int64_t>(options.max_message_bytes, INT32_MAX)));
  builder.SetMaxSendMessageSize(static_cast<int>(std::min<int64_t>(options.max_message_bytes, INT32_MAX)));
  // A client whose process died frees its session at once (the socket closes). One that
  // vanished without closing it (network gone) is found by pings every 10 s with a 20 s
  // timeout. The timeout is generous because a busy sync client acks pings only from gRPC's
  // backup poller (every 5 s) while it computes between reads.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 1000);
  // Step results reach tens of MB; a large stream window lets them flow without waiting for
  // window updates (measured: +3-5 % steps/s at 1024 envs in bench/grpc_transport_bench).
  builder.AddChannelArgument(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 64 << 20);
  // gRPC enables SO_REUSEPORT by default: a second server on a busy port would silently share
  // it. Fail instead.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.RegisterService(service->get());
  running->service_ = *std::move(service);
  running->server_ = builder.BuildAndStart();
  if (running->server_ == nullptr || running->port_ == 0) {
    // gRPC reads the PEM pair only here, and says why only in its log: name the likely cause.
    if (!options.tls_cert_file.empty()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "cannot listen on ", address, " with TLS: tls_cert ", options.tls_cert_file, " and tls_key ",
          options.tls_key_file, " must be a PEM certificate chain and its matching private key (or the port is taken)"));
    }
    return absl::UnavailableError(absl::StrCat("cannot listen on ", address));
  }
  running->server_->GetHealthCheckService()->SetServingStatus(true);
  return running;
}

}  // namespace modskill
