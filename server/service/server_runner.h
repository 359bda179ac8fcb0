// Starts the gRPC server around a SimulationService: listening address, TLS, message limits,
// keepalive (so vanished clients are noticed), health and reflection services.
#ifndef MODSKILL_SERVER_SERVICE_SERVER_RUNNER_H_
#define MODSKILL_SERVER_SERVICE_SERVER_RUNNER_H_

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "server/service/simulation_service.h"

namespace modskill {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  int port = 50051;  // 0: pick a free port
  std::string tls_cert_file;
  std::string tls_key_file;
  int64_t max_message_bytes = int64_t{512} << 20;
  ServiceOptions service;
};

class RunningServer {
 public:
  int port() const { return port_; }
  SimulationService& service() { return *service_; }
  // Stops accepting calls and cancels those still running after `grace`.
  void Shutdown(absl::Duration grace);
  void Wait() { server_->Wait(); }

 private:
  friend absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions&,
                                                                    std::shared_ptr<const MotionLibrary>);
  std::unique_ptr<SimulationService> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options,
                                                           std::shared_ptr<const MotionLibrary> motions);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SERVER_RUNNER_H_
