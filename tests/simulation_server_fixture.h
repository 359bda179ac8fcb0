// What the gRPC server's end-to-end tests share: a server on a free port (3 sessions of at most
// 64 envs, no generative resampling) with a client, a session config, a scratch directory, and a
// raw request sequence for what the client library would refuse to send.
#ifndef MODSKILL_TESTS_SIMULATION_SERVER_FIXTURE_H_
#define MODSKILL_TESTS_SIMULATION_SERVER_FIXTURE_H_

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/policy/policy_checkpoint.h"
#include "server/core/env/policy_fit.h"
#include "tests/server_fixture.h"
#include "tests/test_files.h"

namespace modskill {

inline v1::SessionConfig Config(int envs, uint64_t seed = 1) {
  v1::SessionConfig config;
  config.set_num_envs(envs);
  config.set_seed(seed);
  return config;
}

inline std::string TempDir() { return ProcessTempDir("server"); }

// The open-loop reference as a policy file: a zero residual policy (PD targets = the reference
// pose of the next frame), 5 parts, as TorchScript bytes; for `task`'s observation.
inline std::string OpenLoopPolicyBytes(TaskKind task = TaskKind::kTracking) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  PolicySpec spec = PolicySpecForEnv(MakeEnvSpec(**humanoid, *catalog->Get("5part"), task));
  spec.task = TaskInfoOf(task).name;
  spec.action = ActionMapping{ActionMode::kResidual, 0.5};
  auto bytes = AffinePolicyBytes(spec, {}, {});
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::string();
}

// Sends a raw request sequence and returns the stream's final status.
inline grpc::Status RawSimulate(const RunningServer& server, const std::vector<v1::SimulateRequest>& requests) {
  auto channel = grpc::CreateChannel(absl::StrCat("127.0.0.1:", server.port()), grpc::InsecureChannelCredentials());
  auto stub = v1::Simulation::NewStub(channel);
  grpc::ClientContext context;
  auto stream = stub->Simulate(&context);
  v1::SimulateResponse response;
  for (const auto& request : requests) {
    if (!stream->Write(request)) break;
    if (!stream->Read(&response)) break;
  }
  stream->WritesDone();
  while (stream->Read(&response)) {
  }
  return stream->Finish();
}

class SimulationServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.service.max_sessions = 3;
    options.service.max_envs_per_session = 64;
    options.service.max_upload_bytes = 1 << 20;
    // Generative resampling has its own tests (generative_resampling_test.cc); here clip sets stay fixed.
    options.service.generation.enabled = false;
    options.service.checkpoint_dirs = {TempDir()};  // where ZeroPolicy() writes
    server_ = StartTestServer(options);
    ASSERT_NE(server_, nullptr);
    client_ = ConnectTo(*server_);
    ASSERT_NE(client_, nullptr);
  }
  void TearDown() override { server_->Shutdown(absl::Seconds(1)); }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
};

}  // namespace modskill

#endif  // MODSKILL_TESTS_SIMULATION_SERVER_FIXTURE_H_
