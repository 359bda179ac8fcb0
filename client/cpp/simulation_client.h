// C++ client of a modskill simulation server: channel set-up (TLS, bearer token, message
// limits) and one method per RPC, with gRPC errors turned into absl::Status that name the server.
#ifndef MODSKILL_CLIENT_CPP_SIMULATION_CLIENT_H_
#define MODSKILL_CLIENT_CPP_SIMULATION_CLIENT_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "modskill/v1/modskill.grpc.pb.h"

namespace modskill {

struct ClientOptions {
  std::string server = "127.0.0.1:50051";
  std::string token;        // sent as 'authorization: Bearer <token>' when set
  std::string tls_ca_file;  // PEM roots: connect with TLS when set
  std::string tls_server_name;  // override the name checked in the server certificate
  int64_t max_message_bytes = int64_t{512} << 20;
  absl::Duration connect_timeout = absl::Seconds(10);
  // HTTP/2 pings: a server that stops answering them within keepalive_timeout is declared lost
  // (UNAVAILABLE), so a cut link ends a stream read within keepalive_time + keepalive_timeout.
  // Not shorter: at 5 s + 5 s a learner on a machine loaded with builds lost a live server
  // ("keepalive watchdog timeout" after a 12 s stall). The server's own pings use 10 s + 20 s.
  absl::Duration keepalive_time = absl::Seconds(10);
  absl::Duration keepalive_timeout = absl::Seconds(20);
};

// Reads a token file (whitespace stripped).
absl::StatusOr<std::string> ReadTokenFile(const std::string& path);

// One open Simulate stream.
class SimulationStream {
 public:
  ~SimulationStream();
  const v1::SessionOpened& opened() const { return opened_; }
  const v1::EnvSpec& spec() const { return opened_.spec(); }
  int num_envs() const { return num_envs_; }
  // Sends [num_envs, action_size] actions and waits for the step result.
  absl::Status Step(const float* actions);
  // Split halves of Step, so a caller can work while the server steps.
  absl::Status SendActions(const float* actions);
  // From the next SendActions on, asks the server for this termination distance (m); 0 keeps the
  // session's own. A curriculum calls it between steps.
  void SetTerminationDistance(float distance) { request_.set_termination_distance(distance); }
  // Family sessions: the next SendActions also sends these parameters, [num_envs,
  // len(spec().family())], for each env's episodes from its next reset on (then they are sent
  // no more: the server keeps them).
  void SetFamilyParameters(const std::vector<float>& rows);
  absl::Status ReceiveResult();
  const v1::StepResult& result() const { return response_.step(); }
  // The name of a clip id of this session (StepResult.clip_id, ended_clip_id), following the
  // motion set's updates (generated clips joining); empty for an id never announced.
  const std::string& clip_name(int id) const;
  // Ids the session's motion set holds now (original clips and live generated ones).
  int live_clips() const { return live_clips_; }
  // Half-closes the stream and returns the server's final status.
  absl::Status Close();
  // Drops the stream at once, as a crashed client would.
  void Cancel() { context_.TryCancel(); }
  size_t last_request_bytes() const { return last_request_bytes_; }
  size_t last_response_bytes() const { return last_response_bytes_; }

 private:
  friend class SimulationClient;
  SimulationStream() = default;
  absl::Status Fail(const std::string& what);

  std::string server_;
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::SimulateRequest, v1::SimulateResponse>> stream_;
  v1::SessionOpened opened_;
  v1::SimulateRequest request_;
  v1::SimulateResponse response_;
  int num_envs_ = 0;
  int action_size_ = 0;
  std::vector<std::string> clip_names_;  // by id, removed ones kept (ended episodes still name them)
  int live_clips_ = 0;
  bool closed_ = false;
  size_t last_request_bytes_ = 0;
  size_t last_response_bytes_ = 0;
};

class SimulationClient {
 public:
  // Waits up to connect_timeout for the server to answer.
  static absl::StatusOr<std::unique_ptr<SimulationClient>> Connect(const ClientOptions& options);

  const std::string& server() const { return options_.server; }
  absl::StatusOr<v1::EnvSpec> Describe(const std::string& part_layout = "");
  absl::StatusOr<v1::ListMotionsResponse> ListMotions();
  absl::StatusOr<v1::ServerStats> GetStats();
  // Reads each file and uploads it under its file name.
  absl::StatusOr<v1::AddMotionsResponse> AddMotionFiles(const std::vector<std::string>& paths);
  absl::StatusOr<v1::AddMotionsResponse> AddMotions(const v1::AddMotionsRequest& request);
  absl::StatusOr<v1::SamplerState> ReportFailures(const v1::ReportFailuresRequest& request);
  absl::StatusOr<v1::SampleReferenceAmpResponse> SampleReferenceAmp(const v1::SampleReferenceAmpRequest& request);
  // Collects the metrics; frames go to `on_frame` when the request asks for them.
  absl::StatusOr<std::vector<v1::ClipMetrics>> Rollout(const v1::RolloutRequest& request,
                                                       const std::function<void(const v1::RolloutFrame&)>& on_frame = nullptr);
  // A motor-skill family's policy at task parameters a: ranges, P(a), nearest elites.
  absl::StatusOr<v1::QueryFamilyResponse> QueryFamily(const v1::QueryFamilyRequest& request);
  absl::StatusOr<std::unique_ptr<SimulationStream>> OpenSession(const v1::SessionConfig& config);

 private:
  explicit SimulationClient(const ClientOptions& options) : options_(options) {}
  void Prepare(grpc::ClientContext* context) const;
  absl::Status FromGrpc(const grpc::Status& status, const std::string& rpc) const;

  ClientOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Simulation::Stub> stub_;
};

}  // namespace modskill

#endif  // MODSKILL_CLIENT_CPP_SIMULATION_CLIENT_H_
