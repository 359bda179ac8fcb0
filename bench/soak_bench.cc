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
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_cat.h"
#include "modskill/v1/modskill.grpc.pb.h"
#include "server/core/util/data_paths.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/motion/motion_library.h"
#include "server/service/policy_checkpoint.h"
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

constexpr auto kCallDeadline = std::chrono::seconds(30);  // far above any answer: reaching it is a hang

// ---- What the clients did ------------------------------------------------------------------

struct Tally {
  std::mutex mutex;
  std::map<std::string, std::map<std::string, int64_t>> bad_by_kind;  // kind -> status code -> count
  std::vector<std::string> findings;                                  // first few, printed at the end
  int64_t findings_total = 0;
  std::atomic<int64_t> sessions_opened{0}, sessions_refused{0}, sessions_closed{0}, sessions_killed{0};
  std::atomic<int64_t> steps{0}, env_steps{0}, bad_requests{0}, good_calls{0}, reconnects{0};

  void Finding(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    ++findings_total;
    if (findings.size() < 20) findings.push_back(what);
  }
  // A malformed request's answer: any clean refusal is fine; OK, UNKNOWN, INTERNAL or a deadline
  // is a finding.
  void Bad(const std::string& kind, const grpc::Status& status) {
    ++bad_requests;
    const grpc::StatusCode code = status.error_code();
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++bad_by_kind[kind][CodeName(code)];
    }
    if (code == grpc::OK || code == grpc::UNKNOWN || code == grpc::INTERNAL || code == grpc::DEADLINE_EXCEEDED) {
      Finding(absl::StrCat(kind, ": ", CodeName(code), " ", status.error_message().substr(0, 200)));
    }
  }
  // A well-formed request that failed.
  void Good(const std::string& kind, const grpc::Status& status) {
    ++good_calls;
    if (!status.ok() && status.error_code() != grpc::RESOURCE_EXHAUSTED) {
      Finding(absl::StrCat(kind, " (well-formed): ", CodeName(status.error_code()), " ",
                           status.error_message().substr(0, 200)));
    }
  }
  static std::string CodeName(grpc::StatusCode code) {
    static const char* kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                   "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                   "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED",
                                   "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
    const int index = static_cast<int>(code);
    return index >= 0 && index < 17 ? kNames[index] : absl::StrCat("code ", index);
  }
};

// What every client needs to know of the server: its address and valid names.
struct Target {
  std::string address;
  int port = 0;
  std::vector<std::string> part_layouts;
  std::vector<std::string> clips;
  int action_size = 0;
};

v1::Tensor FloatTensor(int rows, int columns, const std::vector<float>& values) {
  v1::Tensor tensor;
  tensor.add_shape(rows);
  tensor.add_shape(columns);
  tensor.set_dtype(v1::FLOAT32);
  tensor.set_data(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  return tensor;
}

// ---- One client ----------------------------------------------------------------------------

class SoakClient {
 public:
  SoakClient(const Target& target, uint64_t seed, Tally* tally) : target_(target), random_(seed), tally_(tally) {
    Reconnect();
  }

  void RunOnce() {
    const double dice = Uniform(0, 1);
    if (dice < 0.45) {
      Session();
    } else if (dice < 0.55) {
      BadSession();
    } else if (dice < 0.95) {
      BadUnary();
    } else if (dice < 0.97) {
      GarbageBytesOnSocket();
    } else {
      Reconnect();  // the old channel and its connection are dropped as they are
    }
  }

 private:
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(random_); }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(random_); }
  template <typename T>
  const T& Pick(const std::vector<T>& values) { return values[Int(0, static_cast<int>(values.size()) - 1)]; }
  std::string Bytes(size_t size) {
    std::string bytes(size, '\0');
    for (char& c : bytes) c = static_cast<char>(Int(0, 255));
    return bytes;
  }
  // For proto string fields: invalid UTF-8 would be refused by gRPC's parser (as INTERNAL)
  // before the service sees it.
  std::string Text(size_t size) {
    std::string text(size, '\0');
    for (char& c : text) c = static_cast<char>(Int(32, 126));
    return text;
  }

  void Reconnect() {
    grpc::ChannelArguments arguments;
    // Each client gets its own connection, so dropping the channel closes it.
    arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    arguments.SetMaxReceiveMessageSize(64 << 20);
    channel_ = grpc::CreateCustomChannel(target_.address, grpc::InsecureChannelCredentials(), arguments);
    stub_ = Simulation::NewStub(channel_);
    ++tally_->reconnects;
  }

  void Deadline(grpc::ClientContext* context) { context->set_deadline(std::chrono::system_clock::now() + kCallDeadline); }

  v1::SessionConfig ValidConfig() {
    v1::SessionConfig config;
    config.set_num_envs(Int(1, absl::GetFlag(FLAGS_max_envs)));
    config.set_seed(random_());
    if (Int(0, 2) == 0) config.set_part_layout(Pick(target_.part_layouts));
    if (Int(0, 2) == 0) {
      for (int i = Int(1, 3); i > 0; --i) config.add_motions(Pick(target_.clips));
    }
    config.set_amp_obs(static_cast<v1::AmpObs>(Int(1, 3)));
    if (Int(0, 3) == 0) config.set_action_mode(v1::RESIDUAL);
    return config;
  }

  std::vector<float> Actions(int envs) {
    std::vector<float> actions(static_cast<size_t>(envs) * target_.action_size);
    for (float& a : actions) a = static_cast<float>(Uniform(-1, 1));
    return actions;
  }

  // A well-formed session: steps, reports, AMP samples, then a clean close or an abrupt death.
  void Session() {
    grpc::ClientContext context;
    Deadline(&context);
    auto stream = stub_->Simulate(&context);
    v1::SimulateRequest request;
    const v1::SessionConfig config = ValidConfig();
    *request.mutable_config() = config;
    v1::SimulateResponse response;
    if (!stream->Write(request) || !stream->Read(&response)) {
      const grpc::Status status = stream->Finish();
      if (status.error_code() == grpc::RESOURCE_EXHAUSTED) {
        ++tally_->sessions_refused;
      } else {
        tally_->Good("Simulate open", status);
      }
      return;
    }
    ++tally_->sessions_opened;
    const std::string session_id = response.opened().session_id();
    std::vector<std::string> clip_names(response.opened().clip_names().begin(), response.opened().clip_names().end());
    const int envs = config.num_envs();
    const int steps = Int(1, absl::GetFlag(FLAGS_max_steps));
    const int death = Int(0, 3);  // 0: cancel between steps, 1: cancel mid-step, 2-3: clean close
    for (int step = 0; step < steps; ++step) {
      v1::SimulateRequest actions;
      *actions.mutable_actions() = FloatTensor(envs, target_.action_size, Actions(envs));
      if (Int(0, 20) == 0) actions.set_termination_distance(static_cast<float>(Uniform(0.2, 1.0)));
      if (!stream->Write(actions)) break;
      if (death == 1 && step == steps - 1) break;  // dies with a step in flight
      if (!stream->Read(&response)) break;
      ++tally_->steps;
      tally_->env_steps += envs;
      if (Int(0, 40) == 0) Report(session_id, clip_names);
      if (Int(0, 60) == 0) SampleAmp(session_id);
      if (Int(0, 80) == 0) BadReport(session_id, clip_names);
      if (Int(0, 150) == 0) OversizedAmp(session_id);
    }
    if (death <= 1) {
      context.TryCancel();
      stream->Finish();
      ++tally_->sessions_killed;
      return;
    }
    stream->WritesDone();
    tally_->Good("Simulate close", stream->Finish());
    ++tally_->sessions_closed;
  }

  void Report(const std::string& session_id, const std::vector<std::string>& clips) {
    grpc::ClientContext context;
    Deadline(&context);
    v1::ReportFailuresRequest request;
    request.set_session_id(session_id);
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip(Pick(clips));
    failure->set_frame(Int(-1, 0));
    failure->set_terminated(Int(0, 1) == 1);
    v1::SamplerState state;
    tally_->Good("ReportFailures", stub_->ReportFailures(&context, request, &state));
  }

  void SampleAmp(const std::string& session_id) {
    grpc::ClientContext context;
    Deadline(&context);
    v1::SampleReferenceAmpRequest request;
    request.set_session_id(session_id);
    request.set_num_samples(Int(1, 64));
    request.set_seed(random_());
    v1::SampleReferenceAmpResponse response;
    tally_->Good("SampleReferenceAmp", stub_->SampleReferenceAmp(&context, request, &response));
  }

  // Malformed reports on a live session: unknown clips, part errors of the wrong length, a
  // discriminator that is not TorchScript.
  void BadReport(const std::string& session_id, const std::vector<std::string>& clips) {
    grpc::ClientContext context;
    Deadline(&context);
    v1::ReportFailuresRequest request;
    request.set_session_id(session_id);
    const int kind = Int(0, 2);
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip(kind == 0 ? absl::StrCat("no_such_clip_", Int(0, 1 << 20)) : Pick(clips));
    failure->set_terminated(true);
    if (kind == 1) {
      for (int i = Int(7, 40); i > 0; --i) failure->add_part_errors(0.1f);
    }
    if (kind == 2) request.set_discriminator(Bytes(Int(1, 4096)));
    v1::SamplerState state;
    tally_->Bad(absl::StrCat("ReportFailures live session ", std::array<const char*, 3>{"unknown clip", "part errors size", "bad discriminator"}[kind]),
                stub_->ReportFailures(&context, request, &state));
  }

  // More AMP samples than any message holds, for a live session.
  void OversizedAmp(const std::string& session_id) {
    grpc::ClientContext context;
    Deadline(&context);
    v1::SampleReferenceAmpRequest request;
    request.set_session_id(session_id);
    request.set_num_samples(Int(0, 1) ? (1 << 20) + Int(0, 1 << 30) : -Int(1, 100));
    v1::SampleReferenceAmpResponse response;
    tally_->Bad("SampleReferenceAmp live session bad num_samples",
                stub_->SampleReferenceAmp(&context, request, &response));
  }

  // A Simulate stream that is wrong from its first or second message.
  void BadSession() {
    grpc::ClientContext context;
    Deadline(&context);
    auto stream = stub_->Simulate(&context);
    v1::SimulateRequest request;
    v1::SessionConfig config = ValidConfig();
    const int envs = config.num_envs();
    std::string kind;
    bool opens = false;  // the config is valid; the actions are not
    switch (Int(0, 8)) {
      case 0: kind = "unknown clip"; config.add_motions(absl::StrCat("no_such_clip_", Int(0, 1 << 20))); break;
      case 1: kind = "bad part layout"; config.set_part_layout(Int(0, 1) ? "7part" : std::string(Int(200, 20000), 'x')); break;
      case 2: kind = "bad num_envs"; config.set_num_envs(Int(0, 1) ? -Int(0, 5) : 100000 + Int(0, 1 << 20)); break;
      case 3: kind = "bad action mode"; config.set_action_mode(static_cast<v1::ActionMode>(Int(3, 1000))); break;
      case 4: kind = "actions first"; break;
      default: kind = std::array<const char*, 4>{"wrong action size", "NaN actions", "wrong dtype", "torn tensor"}[Int(0, 3)]; opens = true;
    }
    if (kind == "actions first") {
      *request.mutable_actions() = FloatTensor(envs, target_.action_size, Actions(envs));
    } else {
      *request.mutable_config() = config;
    }
    v1::SimulateResponse response;
    if (opens) {
      if (!stream->Write(request) || !stream->Read(&response)) {
        const grpc::Status status = stream->Finish();
        if (status.error_code() == grpc::RESOURCE_EXHAUSTED) ++tally_->sessions_refused;
        else tally_->Good("Simulate open", status);
        return;
      }
      ++tally_->sessions_opened;
      v1::SimulateRequest actions;
      std::vector<float> values = Actions(envs);
      if (kind == "wrong action size") {
        const int columns = target_.action_size + Int(1, 5) * (Int(0, 1) ? 1 : -1);
        values.resize(static_cast<size_t>(envs) * columns);
        *actions.mutable_actions() = FloatTensor(envs, columns, values);
      } else if (kind == "NaN actions") {
        values[Int(0, static_cast<int>(values.size()) - 1)] = Int(0, 1) ? NAN : INFINITY;
        *actions.mutable_actions() = FloatTensor(envs, target_.action_size, values);
      } else if (kind == "wrong dtype") {
        *actions.mutable_actions() = FloatTensor(envs, target_.action_size, values);
        actions.mutable_actions()->set_dtype(static_cast<v1::DType>(Int(2, 9)));
      } else {
        *actions.mutable_actions() = FloatTensor(envs, target_.action_size, values);
        actions.mutable_actions()->mutable_data()->resize(Int(0, static_cast<int>(values.size() * 4) - 1));
      }
      request = actions;
    }
    kind = absl::StrCat("Simulate ", kind);
    if (!stream->Write(request)) {
      tally_->Bad(kind, stream->Finish());
      return;
    }
    // A malformed first message gets no SessionOpened; a bad action batch gets no step result.
    while (stream->Read(&response)) {
      if (response.has_opened() || response.has_step()) {
        context.TryCancel();
        stream->Finish();
        tally_->Bad(kind, grpc::Status::OK);
        return;
      }
    }
    tally_->Bad(kind, stream->Finish());
  }

  // Unary calls with bad arguments.
  void BadUnary() {
    grpc::ClientContext context;
    Deadline(&context);
    switch (Int(0, 7)) {
      case 0: {
        v1::ReportFailuresRequest request;
        request.set_session_id(Int(0, 1) ? absl::StrCat("s", Int(0, 1 << 20)) : Text(Int(1000, 30000)));
        request.add_failures()->set_clip(Pick(target_.clips));
        v1::SamplerState state;
        tally_->Bad("ReportFailures bad session id", stub_->ReportFailures(&context, request, &state));
        return;
      }
      case 1: {
        v1::DescribeRequest request;
        request.set_part_layout(Int(0, 1) ? "no_such_layout" : std::string(Int(1000, 200000), 'p'));
        v1::EnvSpec spec;
        tally_->Bad("Describe bad part layout", stub_->Describe(&context, request, &spec));
        return;
      }
      case 2: {
        v1::SampleReferenceAmpRequest request;
        request.set_num_samples(Int(0, 1) ? (1 << 20) + Int(0, 1 << 30) : -Int(1, 100));
        v1::SampleReferenceAmpResponse response;
        tally_->Bad("SampleReferenceAmp no session, bad num_samples", stub_->SampleReferenceAmp(&context, request, &response));
        return;
      }
      case 3: {
        v1::RolloutRequest request;
        // Random bytes, or random bytes behind a zip signature (TorchScript archives are zips).
        std::string bytes = Bytes(Int(1, 65536));
        if (Int(0, 1)) bytes.replace(0, std::min<size_t>(4, bytes.size()), "PK\x03\x04");
        request.set_checkpoint_bytes(bytes);
        request.add_clips(Pick(target_.clips));
        request.set_max_steps_per_clip(5);
        auto reader = stub_->Rollout(&context, request);
        v1::RolloutResponse response;
        bool answered = false;
        while (reader->Read(&response)) answered = true;
        const grpc::Status status = reader->Finish();
        tally_->Bad("Rollout bad checkpoint bytes", answered && status.ok() ? grpc::Status::OK : status);
        return;
      }
      case 4: {
        v1::RolloutRequest request;
        request.set_checkpoint_path(Int(0, 1) ? "/etc/passwd" : "../../policy.pt");
        auto reader = stub_->Rollout(&context, request);
        v1::RolloutResponse response;
        while (reader->Read(&response)) {
        }
        tally_->Bad("Rollout checkpoint_path", reader->Finish());
        return;
      }
      case 5: {
        v1::AddMotionsRequest request;
        static const char* kExtensions[] = {".bvh", ".npz", ".txt", ".msclip", ".exe", ""};
        for (int i = Int(1, 3); i > 0; --i) {
          v1::MotionUpload* upload = request.add_uploads();
          upload->set_file_name(absl::StrCat("soak", kExtensions[Int(0, 5)]));
          std::string data = Bytes(Int(0, 32768));
          // Sometimes a plausible start, so the parsers get past their first check.
          if (Int(0, 1)) data.insert(0, std::array<const char*, 3>{"HIERARCHY\nROOT Hips\n{\n", "PK\x03\x04", "{\"Loop\": \"none\", \"Frames\": [[0.0333"}[Int(0, 2)]);
          upload->set_data(data);
          if (Int(0, 3) == 0) upload->set_name("../../evil");
        }
        v1::AddMotionsResponse response;
        tally_->Bad("AddMotions garbage", stub_->AddMotions(&context, request, &response));
        return;
      }
      case 6: {
        v1::SampleReferenceAmpRequest request;
        request.set_session_id(absl::StrCat("gone_", Int(0, 1 << 20)));
        request.set_num_samples(8);
        v1::SampleReferenceAmpResponse response;
        tally_->Bad("SampleReferenceAmp bad session id", stub_->SampleReferenceAmp(&context, request, &response));
        return;
      }
      default: {
        v1::ServerStats stats;
        tally_->Good("GetStats", stub_->GetStats(&context, v1::GetStatsRequest(), &stats));
        return;
      }
    }
  }

  // Not gRPC at all: a connection that sends random bytes (or an HTTP/2 preface and then random
  // bytes) and closes.
  void GarbageBytesOnSocket() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return;
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(target_.port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (target_.port > 0 && connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0) {
      std::string bytes = Bytes(Int(1, 4096));
      if (Int(0, 1)) bytes.insert(0, "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n");
      (void)!send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
      ++tally_->bad_requests;
      std::lock_guard<std::mutex> lock(tally_->mutex);
      ++tally_->bad_by_kind["raw socket garbage"]["sent"];
    }
    close(fd);
  }

  const Target& target_;
  std::mt19937_64 random_;
  Tally* tally_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<Simulation::Stub> stub_;
};

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

template <typename T>
T Median(std::vector<T> values) {
  if (values.empty()) return T();
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
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

int Run() {
  const int sessions = absl::GetFlag(FLAGS_sessions);
  const double minutes = absl::GetFlag(FLAGS_minutes);
  std::unique_ptr<RunningServer> server;
  Target target;
  int pid = absl::GetFlag(FLAGS_server_pid);
  if (absl::GetFlag(FLAGS_server).empty()) {
    auto spec = HumanoidSpec::LoadDefault();
    if (!spec.ok()) return Fail(std::string(spec.status().message()));
    auto library = MotionLibrary::LoadDirectory(DataPath("motions"), *spec);
    if (!library.ok()) return Fail(std::string(library.status().message()));
    SetTorchThreads(1);
    ServerOptions options;
    options.bind = "127.0.0.1";
    options.port = 0;
    // Room for every client plus the sessions of killed clients the server is still ending.
    options.service.max_sessions = 2 * sessions;
    auto started = StartServer(options, std::make_shared<const MotionLibrary>(*std::move(library)));
    if (!started.ok()) return Fail(std::string(started.status().message()));
    server = *std::move(started);
    target.port = server->port();
    target.address = absl::StrCat("127.0.0.1:", target.port);
    pid = 0;  // this process
  } else {
    target.address = absl::GetFlag(FLAGS_server);
    const size_t colon = target.address.rfind(':');
    if (target.address.rfind("127.0.0.1:", 0) == 0) target.port = std::atoi(target.address.c_str() + colon + 1);
  }
  {
    auto channel = grpc::CreateChannel(target.address, grpc::InsecureChannelCredentials());
    auto stub = Simulation::NewStub(channel);
    grpc::ClientContext describe_context, list_context;
    describe_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    list_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::EnvSpec spec;
    v1::ListMotionsResponse motions;
    grpc::Status status = stub->Describe(&describe_context, v1::DescribeRequest(), &spec);
    if (status.ok()) status = stub->ListMotions(&list_context, v1::ListMotionsRequest(), &motions);
    if (!status.ok()) return Fail(absl::StrCat(target.address, ": ", status.error_message()));
    target.part_layouts.assign(spec.part_layouts().begin(), spec.part_layouts().end());
    for (const v1::MotionInfo& motion : motions.motions()) target.clips.push_back(motion.name());
    target.action_size = spec.action_size();
  }
  std::printf("soak: %d clients against %s for %.1f min, seed %llu, %zu clips, layouts %zu\n", sessions,
              target.address.c_str(), minutes, static_cast<unsigned long long>(absl::GetFlag(FLAGS_seed)),
              target.clips.size(), target.part_layouts.size());

  Tally tally;
  std::atomic<bool> stop{false};
  std::vector<std::thread> clients;
  for (int i = 0; i < sessions; ++i) {
    clients.emplace_back([&, i] {
      SoakClient client(target, absl::GetFlag(FLAGS_seed) + static_cast<uint64_t>(i), &tally);
      while (!stop.load()) client.RunOnce();
    });
  }

  std::vector<Sample> samples;
  const auto start = Clock::now();
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

  // Every client has left: the server must hold no session after a short grace.
  int32_t still_open = -1;
  if (server != nullptr) {
    auto stub = Simulation::NewStub(grpc::CreateChannel(target.address, grpc::InsecureChannelCredentials()));
    for (int attempt = 0; attempt < 50; ++attempt) {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
      v1::ServerStats stats;
      if (stub->GetStats(&context, v1::GetStatsRequest(), &stats).ok()) still_open = stats.active_sessions();
      if (still_open == 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }

  std::vector<int64_t> rss;
  std::vector<int> fds;
  for (const Sample& sample : samples) {
    rss.push_back(sample.rss_kb);
    fds.push_back(sample.fds);
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
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
  if (server != nullptr) server->Shutdown(absl::Seconds(2));
  return pass ? 0 : 1;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::Run();
}
