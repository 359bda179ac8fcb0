// Transport cost (docs/DESIGN.md section 5: a learner over loopback gRPC gets >= 0.9 x the steps/s
// of the same envs in-process).
//
// For 64, 256 and 1024 envs and 1 and 2 server threads: a learner-like loop (send zero actions,
// wait for the step result, decode obs and rewards) against an in-process server over loopback,
// versus the same EnvBatch stepped in-process with the same actions. Configurations interleave
// and repeat; medians are reported with the message sizes and the per-step latency.
#include <malloc.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_cat.h"
#include "bench/median.h"
#include "client/cpp/simulation_client.h"
#include "common/wire/tensor_codec.h"
#include "server/service/server_runner.h"

ABSL_FLAG(int, repeats, 3, "measurements per configuration (median reported)");
ABSL_FLAG(double, seconds, 2.0, "seconds per measurement");
ABSL_FLAG(std::string, amp_obs, "full", "AMP observation sent per step: full, newest or omit");

namespace modskill {
namespace {

using Clock = std::chrono::steady_clock;

struct Measurement {
  double env_steps_per_second = 0;
  double step_latency_ms = 0;  // median wall time of one batch step
};

Measurement InProcess(EnvBatch* batch, double seconds) {
  std::vector<float> actions(static_cast<size_t>(batch->num_envs()) * batch->spec().action_size, 0.f);
  batch->Reset();
  std::vector<double> latencies;
  const auto start = Clock::now();
  int64_t env_steps = 0;
  while (std::chrono::duration<double>(Clock::now() - start).count() < seconds) {
    const auto t0 = Clock::now();
    if (!batch->Step(actions).ok()) return {};
    latencies.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    env_steps += batch->num_envs();
  }
  return {env_steps / std::chrono::duration<double>(Clock::now() - start).count(), Median(latencies)};
}

Measurement OverGrpc(SimulationClient* client, int envs, v1::AmpObs amp, double seconds, size_t* request_bytes,
                     size_t* response_bytes) {
  v1::SessionConfig config;
  config.set_num_envs(envs);
  config.set_seed(1);
  config.set_amp_obs(amp);
  auto stream = client->OpenSession(config);
  if (!stream.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(stream.status().message()).c_str());
    return {};
  }
  std::vector<float> actions(static_cast<size_t>(envs) * (*stream)->spec().action_size(), 0.f);
  std::vector<float> obs, reward;
  std::vector<double> latencies;
  const auto start = Clock::now();
  int64_t env_steps = 0;
  while (std::chrono::duration<double>(Clock::now() - start).count() < seconds) {
    const auto t0 = Clock::now();
    if (!(*stream)->Step(actions.data()).ok()) return {};
    // What a learner does with every result: decode what it trains on.
    if (!ReadFloatTensor((*stream)->result().obs(), "obs", &obs).ok()) return {};
    if (!ReadFloatTensor((*stream)->result().reward(), "reward", &reward).ok()) return {};
    latencies.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    env_steps += envs;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  *request_bytes = (*stream)->last_request_bytes();
  *response_bytes = (*stream)->last_response_bytes();
  (void)(*stream)->Close();
  return {env_steps / elapsed, Median(latencies)};
}

int Run() {
  const std::string amp_name = absl::GetFlag(FLAGS_amp_obs);
  v1::AmpObs amp = v1::FULL;
  if (amp_name == "newest") amp = v1::NEWEST;
  else if (amp_name == "omit") amp = v1::OMIT;
  else if (amp_name != "full") return std::fprintf(stderr, "error: --amp_obs must be full, newest or omit\n"), 2;
  auto spec = HumanoidSpec::LoadDefault();
  auto library = MotionLibrary::LoadDefault(*spec);
  if (!spec.ok() || !library.ok()) return std::fprintf(stderr, "error: cannot load the default data\n"), 1;
  auto motions = std::make_shared<const MotionLibrary>(*std::move(library));
  const double seconds = absl::GetFlag(FLAGS_seconds);
  std::printf("zero actions, amp_obs %s, %d repeats x %.1f s, medians; server and client share this machine\n",
              amp_name.c_str(), absl::GetFlag(FLAGS_repeats), seconds);
  std::printf("%6s %8s %14s %14s %7s %12s %12s %12s %12s\n", "envs", "threads", "in-process/s", "grpc/s", "ratio",
              "request KB", "response KB", "local ms", "grpc ms");
  for (int threads : {1, 2}) {
    ServerOptions options;
    options.port = 0;
    options.service.threads_per_session = threads;
    auto server = StartServer(options, motions);
    if (!server.ok()) return std::fprintf(stderr, "error: %s\n", std::string(server.status().message()).c_str()), 1;
    ClientOptions client_options;
    client_options.server = absl::StrCat("127.0.0.1:", (*server)->port());
    auto client = SimulationClient::Connect(client_options);
    if (!client.ok()) return std::fprintf(stderr, "error: %s\n", std::string(client.status().message()).c_str()), 1;
    for (int envs : {64, 256, 1024}) {
      EnvBatchConfig config;
      config.num_envs = envs;
      config.num_threads = threads;
      config.seed = 1;
      auto batch = EnvBatch::Create(config, motions);
      if (!batch.ok()) return 1;
      std::vector<double> local_rate, grpc_rate, local_ms, grpc_ms;
      size_t request_bytes = 0, response_bytes = 0;
      for (int r = 0; r < absl::GetFlag(FLAGS_repeats); ++r) {
        const Measurement local = InProcess(batch->get(), seconds);
        const Measurement remote = OverGrpc(client->get(), envs, amp, seconds, &request_bytes, &response_bytes);
        local_rate.push_back(local.env_steps_per_second);
        grpc_rate.push_back(remote.env_steps_per_second);
        local_ms.push_back(local.step_latency_ms);
        grpc_ms.push_back(remote.step_latency_ms);
      }
      std::printf("%6d %8d %14.0f %14.0f %7.3f %12.1f %12.1f %12.2f %12.2f\n", envs, threads, Median(local_rate),
                  Median(grpc_rate), Median(grpc_rate) / Median(local_rate), request_bytes / 1024.0,
                  response_bytes / 1024.0, Median(local_ms), Median(grpc_ms));
      std::fflush(stdout);
    }
    (*server)->Shutdown(absl::Seconds(1));
  }
  return 0;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  if (std::getenv("BENCH_MALLOPT")) {
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
  }
  return modskill::Run();
}
