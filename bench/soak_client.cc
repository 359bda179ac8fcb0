#include "bench/soak_client.h"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>

#include "modskill/v1/modskill.grpc.pb.h"

namespace modskill {
namespace {

using v1::Simulation;

constexpr auto kCallDeadline = std::chrono::seconds(30);  // far above any answer: reaching it is a hang

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
    config.set_num_envs(Int(1, target_.max_envs));
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
    const int steps = Int(1, target_.max_steps);
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
      case 3:
        BadCheckpointBytes(context);
        return;
      case 4:
        BadCheckpointPath(context);
        return;
      case 5:
        GarbageUploads(context);
        return;
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

  // A Rollout whose checkpoint bytes are random.
  void BadCheckpointBytes(grpc::ClientContext& context) {
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
  }

  // A Rollout naming a checkpoint path outside any --checkpoint_dir.
  void BadCheckpointPath(grpc::ClientContext& context) {
    v1::RolloutRequest request;
    request.set_checkpoint_path(Int(0, 1) ? "/etc/passwd" : "../../policy.pt");
    auto reader = stub_->Rollout(&context, request);
    v1::RolloutResponse response;
    while (reader->Read(&response)) {
    }
    tally_->Bad("Rollout checkpoint_path", reader->Finish());
  }

  // AddMotions with random (or plausibly starting) file contents and names.
  void GarbageUploads(grpc::ClientContext& context) {
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

}  // namespace

void RunSoakClient(const Target& target, uint64_t seed, Tally* tally, const std::atomic<bool>& stop) {
  SoakClient client(target, seed, tally);
  while (!stop.load()) client.RunOnce();
}

}  // namespace modskill
