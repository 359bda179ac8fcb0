// Soak test (issue 10; a benchmark, not in CI): many concurrent clients that open Simulate
// sessions, step for random lengths, die abruptly, send malformed requests and reconnect, for
// minutes, while the server's resident memory and open file descriptors are sampled. They must
// stay flat: after warm-up (the first quarter), the last quarter's median RSS may be at most
// --max_rss_ratio times the second quarter's, and its median fd count at most --max_fd_growth
// above. Also fails on a bad request the server accepted, an unclean status (UNKNOWN, INTERNAL)
// or a call that ran into its deadline (a hang), and on sessions still open after every client left.
//
//   soak_bench [--minutes 10] [--sessions 32] [--seed 1] [--server host:port --server_pid PID]
//
// Without --server it starts the server in this process on 127.0.0.1 (its figures then include
// the clients' own memory, which must stay flat too).
#include <dirent.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "bench/median.h"
#include "bench/soak_client.h"
#include "common/policy/policy_checkpoint.h"
#include "modskill/v1/modskill.grpc.pb.h"
#include "server/core/motion/motion_library.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/util/data_paths.h"
#include "server/service/server_runner.h"

ABSL_FLAG(double, minutes, 10.0, "how long the clients run");
ABSL_FLAG(int, sessions, 32, "concurrent clients (threads), each with at most one session open");
ABSL_FLAG(uint64_t, seed, 1, "seed of every random choice (client i draws from seed + i)");
ABSL_FLAG(std::string, server, "", "host:port of a running server; empty: start one in this process");
ABSL_FLAG(int, server_pid, 0, "with --server: the server's process id, whose RSS and fds are sampled");
ABSL_FLAG(double, sample_seconds, 5.0, "seconds between resource samples");
ABSL_FLAG(int, max_envs, 4, "envs per session, drawn from [1, max_envs]");
ABSL_FLAG(int, max_steps, 150, "steps per session, drawn from [1, max_steps]");
ABSL_FLAG(double, max_rss_ratio, 1.25, "bound: last-quarter median RSS / second-quarter median RSS");
ABSL_FLAG(int, max_fd_growth, 16, "bound: last-quarter median fds - second-quarter median fds");

namespace modskill {
namespace {

using Clock = std::chrono::steady_clock;
using v1::Simulation;

// ---- Resources -----------------------------------------------------------------------------

struct Sample {
  double seconds = 0;
  int64_t rss_kb = 0;
  int fds = 0;
  int64_t sessions_opened = 0;
  int64_t bad_requests = 0;
  int64_t env_steps = 0;
};

int64_t RssKb(int pid) {
  std::ifstream status(pid > 0 ? absl::StrCat("/proc/", pid, "/status") : "/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
  }
  return -1;
}

int OpenFds(int pid) {
  DIR* directory = opendir(pid > 0 ? absl::StrCat("/proc/", pid, "/fd").c_str() : "/proc/self/fd");
  if (directory == nullptr) return -1;
  int count = 0;
  while (dirent* entry = readdir(directory)) count += entry->d_name[0] != '.';
  closedir(directory);
  return count - (pid > 0 ? 0 : 1);  // not the directory's own fd
}

// Medians of one quarter of the samples (0-based).
template <typename T>
T QuarterMedian(const std::vector<Sample>& samples, int quarter, T Sample::*field) {
  const size_t begin = samples.size() * quarter / 4, end = samples.size() * (quarter + 1) / 4;
  std::vector<T> values;
  for (size_t i = begin; i < end; ++i) values.push_back(samples[i].*field);
  return Median(values);
}

// ---- Main ----------------------------------------------------------------------------------

int Fail(const std::string& what) {
  std::fprintf(stderr, "error: %s\n", what.c_str());
  return 1;
}

// The server the clients soak: one started in this process (--server empty), or --server.
struct ServerUnderTest {
  std::unique_ptr<RunningServer> server;  // null for --server
  Target target;
  int pid = 0;  // whose RSS and fds are sampled; 0: this process
};

absl::Status StartOrFindServer(int sessions, ServerUnderTest* out) {
  Target& target = out->target;
  out->pid = absl::GetFlag(FLAGS_server_pid);
  if (!absl::GetFlag(FLAGS_server).empty()) {
    target.address = absl::GetFlag(FLAGS_server);
    const size_t colon = target.address.rfind(':');
    if (target.address.rfind("127.0.0.1:", 0) == 0) target.port = std::atoi(target.address.c_str() + colon + 1);
    return absl::OkStatus();
  }
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return spec.status();
  auto library = MotionLibrary::LoadDirectory(DataPath("motions"), *spec);
  if (!library.ok()) return library.status();
  SetTorchThreads(1);
  ServerOptions options;
  options.bind = "127.0.0.1";
  options.port = 0;
  // Room for every client plus the sessions of killed clients the server is still ending.
  options.service.max_sessions = 2 * sessions;
  auto started = StartServer(options, std::make_shared<const MotionLibrary>(*std::move(library)));
  if (!started.ok()) return started.status();
  out->server = *std::move(started);
  target.port = out->server->port();
  target.address = absl::StrCat("127.0.0.1:", target.port);
  out->pid = 0;  // this process
  return absl::OkStatus();
}

// The server's part layouts, clips and action size, which the clients draw from.
absl::Status DescribeTarget(Target* target) {
  auto channel = grpc::CreateChannel(target->address, grpc::InsecureChannelCredentials());
  auto stub = Simulation::NewStub(channel);
  grpc::ClientContext describe_context, list_context;
  describe_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  list_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  v1::EnvSpec spec;
  v1::ListMotionsResponse motions;
  grpc::Status status = stub->Describe(&describe_context, v1::DescribeRequest(), &spec);
  if (status.ok()) status = stub->ListMotions(&list_context, v1::ListMotionsRequest(), &motions);
  if (!status.ok()) return absl::UnavailableError(absl::StrCat(target->address, ": ", status.error_message()));
  target->part_layouts.assign(spec.part_layouts().begin(), spec.part_layouts().end());
  for (const v1::MotionInfo& motion : motions.motions()) target->clips.push_back(motion.name());
  target->action_size = spec.action_size();
  return absl::OkStatus();
}

// Runs the clients for --minutes while sampling the server's resources every --sample_seconds
// (one line each); returns the samples once every client has stopped.
std::vector<Sample> SoakAndSample(const Target& target, int sessions, double minutes, int pid, Tally& tally,
                                  Clock::time_point* start_out) {
  std::atomic<bool> stop{false};
  std::vector<std::thread> clients;
  for (int i = 0; i < sessions; ++i) {
    clients.emplace_back([&, i] {
      RunSoakClient(target, absl::GetFlag(FLAGS_seed) + static_cast<uint64_t>(i), &tally, stop);
    });
  }

  std::vector<Sample> samples;
  const auto start = Clock::now();
  *start_out = start;
  const auto end = start + std::chrono::duration<double>(minutes * 60);
  std::printf("%8s %10s %6s %10s %10s %12s\n", "t (s)", "RSS (MiB)", "fds", "sessions", "bad reqs", "env steps");
  for (auto next = start; next <= end; next += std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(absl::GetFlag(FLAGS_sample_seconds)))) {
    std::this_thread::sleep_until(next);
    Sample sample;
    sample.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    sample.rss_kb = RssKb(pid);
    sample.fds = OpenFds(pid);
    sample.sessions_opened = tally.sessions_opened;
    sample.bad_requests = tally.bad_requests;
    sample.env_steps = tally.env_steps;
    samples.push_back(sample);
    std::printf("%8.0f %10.1f %6d %10lld %10lld %12lld\n", sample.seconds, sample.rss_kb / 1024.0, sample.fds,
                static_cast<long long>(sample.sessions_opened), static_cast<long long>(sample.bad_requests),
                static_cast<long long>(sample.env_steps));
    std::fflush(stdout);
  }
  stop = true;
  for (std::thread& client : clients) client.join();
  return samples;
}

// Every client has left: the sessions the server still holds after a short grace (-1: unknown).
int32_t SessionsLeftOpen(const std::string& address) {
  int32_t still_open = -1;
  auto stub = Simulation::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  for (int attempt = 0; attempt < 50; ++attempt) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::ServerStats stats;
    if (stub->GetStats(&context, v1::GetStatsRequest(), &stats).ok()) still_open = stats.active_sessions();
    if (still_open == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return still_open;
}

// What the clients did: sessions, steps, calls, and the answers to each kind of bad request.
void PrintTally(const Tally& tally, double elapsed) {
  std::printf("\nran %.0f s: %lld sessions opened (%lld closed cleanly, %lld killed, %lld refused busy), "
              "%lld steps (%lld env steps), %lld bad requests, %lld well-formed unary calls, %lld reconnects\n",
              elapsed, static_cast<long long>(tally.sessions_opened.load()),
              static_cast<long long>(tally.sessions_closed.load()), static_cast<long long>(tally.sessions_killed.load()),
              static_cast<long long>(tally.sessions_refused.load()), static_cast<long long>(tally.steps.load()),
              static_cast<long long>(tally.env_steps.load()), static_cast<long long>(tally.bad_requests.load()),
              static_cast<long long>(tally.good_calls.load()), static_cast<long long>(tally.reconnects.load()));
  std::printf("\nbad requests by kind and answer:\n");
  for (const auto& [kind, codes] : tally.bad_by_kind) {
    std::string line;
    for (const auto& [code, count] : codes) absl::StrAppend(&line, " ", code, "=", count);
    std::printf("  %-45s%s\n", kind.c_str(), line.c_str());
  }
}

// The resource table and the verdict: RSS and fds flat, no session left open, no finding.
bool PrintVerdict(const std::vector<Sample>& samples, int32_t still_open, const Tally& tally) {
  std::vector<int64_t> rss;
  std::vector<int> fds;
  for (const Sample& sample : samples) {
    rss.push_back(sample.rss_kb);
    fds.push_back(sample.fds);
  }
  const int64_t rss_q2 = QuarterMedian(samples, 1, &Sample::rss_kb), rss_q4 = QuarterMedian(samples, 3, &Sample::rss_kb);
  const int fds_q2 = QuarterMedian(samples, 1, &Sample::fds), fds_q4 = QuarterMedian(samples, 3, &Sample::fds);
  std::printf("\n%-10s %10s %10s %10s %10s %14s %14s\n", "", "first", "median", "last", "max", "2nd-qtr median",
              "4th-qtr median");
  std::printf("%-10s %10.1f %10.1f %10.1f %10.1f %14.1f %14.1f\n", "RSS (MiB)", rss.front() / 1024.0,
              Median(rss) / 1024.0, rss.back() / 1024.0, *std::max_element(rss.begin(), rss.end()) / 1024.0,
              rss_q2 / 1024.0, rss_q4 / 1024.0);
  std::printf("%-10s %10d %10d %10d %10d %14d %14d\n", "fds", fds.front(), Median(fds), fds.back(),
              *std::max_element(fds.begin(), fds.end()), fds_q2, fds_q4);

  bool pass = true;
  const double ratio = rss_q2 > 0 ? static_cast<double>(rss_q4) / rss_q2 : 0;
  if (samples.size() < 8) {
    std::printf("FAIL: %zu samples; run longer for a verdict\n", samples.size());
    pass = false;
  }
  if (rss_q2 <= 0 || ratio > absl::GetFlag(FLAGS_max_rss_ratio)) {
    std::printf("FAIL: RSS grew: last-quarter median / second-quarter median = %.3f (bound %.2f)\n", ratio,
                absl::GetFlag(FLAGS_max_rss_ratio));
    pass = false;
  }
  if (fds_q4 - fds_q2 > absl::GetFlag(FLAGS_max_fd_growth)) {
    std::printf("FAIL: fds grew by %d (bound %d)\n", fds_q4 - fds_q2, absl::GetFlag(FLAGS_max_fd_growth));
    pass = false;
  }
  if (still_open > 0) {
    std::printf("FAIL: %d sessions still open 5 s after every client left\n", still_open);
    pass = false;
  }
  if (tally.findings_total > 0) {
    std::printf("FAIL: %lld unexpected answers (a bad request accepted, UNKNOWN/INTERNAL, a deadline), first ones:\n",
                static_cast<long long>(tally.findings_total));
    for (const std::string& finding : tally.findings) std::printf("  %s\n", finding.c_str());
    pass = false;
  }
  std::printf("%s: RSS ratio %.3f (bound %.2f), fd growth %d (bound %d), sessions left open %d\n",
              pass ? "PASS" : "FAIL", ratio, absl::GetFlag(FLAGS_max_rss_ratio), fds_q4 - fds_q2,
              absl::GetFlag(FLAGS_max_fd_growth), std::max(still_open, 0));
  return pass;
}

int Run() {
  const int sessions = absl::GetFlag(FLAGS_sessions);
  const double minutes = absl::GetFlag(FLAGS_minutes);
  ServerUnderTest under_test;
  if (absl::Status status = StartOrFindServer(sessions, &under_test); !status.ok()) {
    return Fail(std::string(status.message()));
  }
  Target& target = under_test.target;
  target.max_envs = absl::GetFlag(FLAGS_max_envs);
  target.max_steps = absl::GetFlag(FLAGS_max_steps);
  if (absl::Status status = DescribeTarget(&target); !status.ok()) return Fail(std::string(status.message()));
  std::printf("soak: %d clients against %s for %.1f min, seed %llu, %zu clips, layouts %zu\n", sessions,
              target.address.c_str(), minutes, static_cast<unsigned long long>(absl::GetFlag(FLAGS_seed)),
              target.clips.size(), target.part_layouts.size());

  Tally tally;
  Clock::time_point start;
  const std::vector<Sample> samples = SoakAndSample(target, sessions, minutes, under_test.pid, tally, &start);
  const int32_t still_open = under_test.server != nullptr ? SessionsLeftOpen(target.address) : -1;
  PrintTally(tally, std::chrono::duration<double>(Clock::now() - start).count());
  const bool pass = PrintVerdict(samples, still_open, tally);
  if (under_test.server != nullptr) under_test.server->Shutdown(absl::Seconds(2));
  return pass ? 0 : 1;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::Run();
}
