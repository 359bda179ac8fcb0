// The gRPC server end to end: the contract, equality with the in-process core, every bad
// input answered with the right status, concurrent and vanishing clients, auth.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "server/core/curriculum/adaptive_sampler.h"
#include "server/service/policy_checkpoint.h"
#include "tests/server_fixture.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

v1::SessionConfig Config(int envs, uint64_t seed = 1) {
  v1::SessionConfig config;
  config.set_num_envs(envs);
  config.set_seed(seed);
  return config;
}

std::string TempDir() {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/server";
  std::filesystem::create_directories(dir);
  return dir;
}

std::string ZeroPolicy(const std::string& layout_name = "5part") {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  const EnvSpec spec = MakeEnvSpec(**humanoid, *catalog->Get(layout_name));
  const std::string path = TempDir() + "/zero_" + layout_name + ".pt";
  EXPECT_TRUE(SaveAffinePolicy(path, PolicySpec::FromEnvSpec(spec), {}, {}).ok());
  return path;
}

// Sends a raw request sequence and returns the stream's final status.
grpc::Status RawSimulate(const RunningServer& server, const std::vector<v1::SimulateRequest>& requests) {
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

TEST_F(SimulationServerTest, DescribeShipsTheLayout) {
  auto spec = client_->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->obs_size(), 934);
  EXPECT_EQ(spec->action_size(), 69);
  EXPECT_EQ(spec->amp_obs_per_frame(), 232);
  EXPECT_EQ(spec->amp_history(), 10);
  EXPECT_EQ(spec->part_layout(), "5part");
  ASSERT_EQ(spec->parts_size(), 5);
  EXPECT_EQ(spec->parts(0).name(), "L_Leg");
  EXPECT_EQ(spec->parts(0).action().size(), 12);
  EXPECT_EQ(spec->parts(2).bodies(0), "Pelvis");
  EXPECT_EQ(spec->body_names_size(), 24);
  EXPECT_EQ(spec->joint_names_size(), 69);
  EXPECT_EQ(spec->action_offset_size(), 69);
  EXPECT_NEAR(spec->control_dt(), 1.0 / 30, 1e-9);
  EXPECT_EQ(spec->num_motions(), DefaultMotions()->size());
  EXPECT_EQ(spec->reward_terms_size(), kNumRewardTerms);
  EXPECT_EQ(spec->part_layouts_size(), 4);
  EXPECT_THAT(std::vector<std::string>(spec->action_modes().begin(), spec->action_modes().end()),
              ::testing::ElementsAre("absolute", "residual"));
  EXPECT_THAT(std::vector<std::string>(spec->termination_bodies().begin(), spec->termination_bodies().end()),
              ::testing::ElementsAre("all", "no_feet"));
  auto three = client_->Describe("3part");
  ASSERT_TRUE(three.ok());
  EXPECT_EQ(three->parts_size(), 3);
  auto unknown = client_->Describe("4part");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(unknown.status().message()), HasSubstr("4part"));
}

// The server's results are the core's, bit for bit, for the same seed and actions.
TEST_F(SimulationServerTest, SessionEqualsInProcessEnvBatch) {
  v1::SessionConfig config = Config(6, 77);
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  EnvBatchConfig local_config;
  local_config.num_envs = 6;
  local_config.seed = 77;
  auto local = MakeBatch(local_config);
  local->Reset();
  std::vector<float> obs;
  ASSERT_TRUE(DecodeFloatTensor((*stream)->opened().initial().obs(), "obs", &obs).ok());
  ASSERT_EQ(obs, local->buffers().obs);
  EXPECT_EQ((*stream)->opened().clip_names_size(), DefaultMotions()->size());
  for (int s = 0; s < 12; ++s) {
    const std::vector<float> actions = ReferenceActions(*local);
    ASSERT_TRUE(local->Step(actions).ok());
    ASSERT_TRUE((*stream)->Step(actions.data()).ok());
    const v1::StepResult& result = (*stream)->result();
    EXPECT_EQ(result.step(), s + 1);
    std::vector<float> remote;
    ASSERT_TRUE(DecodeFloatTensor(result.obs(), "obs", &remote).ok());
    ASSERT_EQ(remote, local->buffers().obs) << s;
    ASSERT_TRUE(DecodeFloatTensor(result.reward(), "reward", &remote).ok());
    ASSERT_EQ(remote, local->buffers().reward) << s;
    ASSERT_TRUE(DecodeFloatTensor(result.amp_obs(), "amp_obs", &remote).ok());
    ASSERT_EQ(remote, local->buffers().amp_obs) << s;
    ASSERT_EQ(result.done().data(), std::string(local->buffers().done.begin(), local->buffers().done.end()));
    ASSERT_EQ(result.clip_id().shape(0), 6);
    ASSERT_EQ(std::memcmp(result.clip_id().data().data(), local->buffers().clip_id.data(), 6 * 4), 0);
  }
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST_F(SimulationServerTest, AmpObsCanBeTheNewestFrameOrOmitted) {
  v1::SessionConfig config = Config(3);
  config.set_amp_obs(v1::NEWEST);
  auto newest = client_->OpenSession(config);
  ASSERT_TRUE(newest.ok());
  EXPECT_EQ((*newest)->opened().initial().amp_obs().shape(1), 232);
  EXPECT_EQ((*newest)->opened().initial().amp_obs().data().size(), 3u * 232 * 4);
  config.set_amp_obs(v1::OMIT);
  auto omitted = client_->OpenSession(config);
  ASSERT_TRUE(omitted.ok());
  EXPECT_FALSE((*omitted)->opened().initial().has_amp_obs());
}

TEST_F(SimulationServerTest, BadSessionConfigsAreRejected) {
  struct Case {
    v1::SessionConfig config;
    absl::StatusCode code;
    std::string message;
  };
  std::vector<Case> cases;
  cases.push_back({Config(0), absl::StatusCode::kInvalidArgument, "num_envs"});
  cases.push_back({Config(65), absl::StatusCode::kResourceExhausted, "num_envs"});
  v1::SessionConfig config = Config(2);
  config.add_motions("deepmimic_walk");
  config.add_motions("no_such_clip");
  cases.push_back({config, absl::StatusCode::kNotFound, "no_such_clip"});
  config = Config(2);
  config.set_part_layout("6part");
  cases.push_back({config, absl::StatusCode::kNotFound, "6part"});
  config = Config(2);
  config.set_termination_distance(std::nanf(""));
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "termination_distance"});
  config = Config(2);
  config.set_max_episode_steps(-3);
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "max_episode_steps"});
  config = Config(2);
  config.set_termination(static_cast<v1::TerminationMode>(17));
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "termination"});
  config = Config(2);
  config.set_action_mode(static_cast<v1::ActionMode>(9));
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "action_mode"});
  for (float scale : {-0.5f, std::nanf(""), std::numeric_limits<float>::infinity(), 11.f}) {
    config = Config(2);
    config.set_action_mode(v1::RESIDUAL);
    config.set_residual_scale(scale);
    cases.push_back({config, absl::StatusCode::kInvalidArgument, "residual_scale"});
  }
  config = Config(2);
  config.set_residual_scale(0.3f);  // absolute mode has no residual scale
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "residual_scale"});
  config = Config(2);
  config.set_termination_bodies(static_cast<v1::TerminationBodies>(5));
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "termination_bodies"});
  for (const Case& c : cases) {
    auto stream = client_->OpenSession(c.config);
    ASSERT_FALSE(stream.ok()) << c.message;
    EXPECT_EQ(stream.status().code(), c.code) << stream.status();
    EXPECT_THAT(std::string(stream.status().message()), HasSubstr(c.message));
  }
}

// A curriculum moves the termination distance between steps; bad values end only that session.
TEST_F(SimulationServerTest, TerminationDistanceChangesMidStream) {
  v1::SessionConfig config = Config(4, 7);
  config.add_motions("cmu_02_01");
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  std::vector<float> zeros(4 * 69, 0.f);  // absolute zeros: every character falls
  auto terminations = [&](int steps) {  // episodes ended by the distance, not the clip's end
    int ended = 0;
    for (int s = 0; s < steps; ++s) {
      EXPECT_TRUE((*stream)->Step(zeros.data()).ok());
      const std::string& done = (*stream)->result().done().data();
      const std::string& truncated = (*stream)->result().truncated().data();
      for (size_t i = 0; i < done.size(); ++i) ended += done[i] && !truncated[i];
    }
    return ended;
  };
  (*stream)->SetTerminationDistance(100);
  EXPECT_EQ(terminations(10), 0);
  (*stream)->SetTerminationDistance(0.001f);
  EXPECT_GE(terminations(4), 4);
  for (float bad : {-1.f, 100.5f, std::nanf("")}) {
    v1::SimulateRequest first;
    *first.mutable_config() = Config(2);
    v1::SimulateRequest step;
    v1::Tensor* t = step.mutable_actions();
    t->add_shape(2);
    t->add_shape(69);
    t->set_dtype(v1::FLOAT32);
    t->set_data(std::string(2 * 69 * 4, '\0'));
    step.set_termination_distance(bad);
    grpc::Status status = RawSimulate(*server_, {first, step});
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_THAT(status.error_message(), HasSubstr("termination_distance"));
  }
  EXPECT_TRUE((*stream)->Step(zeros.data()).ok());
}

TEST_F(SimulationServerTest, FirstMessageMustBeTheConfig) {
  v1::SimulateRequest actions;
  actions.mutable_actions()->set_dtype(v1::FLOAT32);
  grpc::Status status = RawSimulate(*server_, {actions});
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("config"));
  status = RawSimulate(*server_, {});
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(SimulationServerTest, BadActionsEndOnlyThatSession) {
  auto healthy = client_->OpenSession(Config(2, 3));
  ASSERT_TRUE(healthy.ok());
  std::vector<float> zeros(2 * 69, 0.f);
  auto expect_error = [&](const std::function<void(v1::SimulateRequest*)>& mutate, const std::string& needle) {
    v1::SimulateRequest config;
    *config.mutable_config() = Config(2);
    v1::SimulateRequest step;
    v1::Tensor* t = step.mutable_actions();
    t->add_shape(2);
    t->add_shape(69);
    t->set_dtype(v1::FLOAT32);
    t->set_data(std::string(reinterpret_cast<const char*>(zeros.data()), zeros.size() * 4));
    mutate(&step);
    grpc::Status status = RawSimulate(*server_, {config, step});
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << needle;
    EXPECT_THAT(status.error_message(), HasSubstr(needle));
    // The healthy session keeps stepping.
    ASSERT_TRUE((*healthy)->Step(zeros.data()).ok()) << needle;
  };
  expect_error([](v1::SimulateRequest* r) { r->mutable_actions()->set_shape(1, 68); }, "actions.shape");
  expect_error([](v1::SimulateRequest* r) { r->mutable_actions()->set_dtype(v1::INT32); }, "actions.dtype");
  expect_error([](v1::SimulateRequest* r) { r->mutable_actions()->mutable_data()->resize(100); }, "actions.data");
  expect_error(
      [](v1::SimulateRequest* r) {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        std::memcpy(&(*r->mutable_actions()->mutable_data())[(69 + 4) * 4], &nan, 4);
      },
      "row 1");
  expect_error(
      [](v1::SimulateRequest* r) {
        const float inf = std::numeric_limits<float>::infinity();
        std::memcpy(&(*r->mutable_actions()->mutable_data())[0], &inf, 4);
      },
      "row 0");
  expect_error([](v1::SimulateRequest* r) { *r->mutable_config() = Config(2); }, "actions");
  EXPECT_TRUE((*healthy)->Close().ok());
}

TEST_F(SimulationServerTest, TooManySessionsIsResourceExhausted) {
  std::vector<std::unique_ptr<SimulationStream>> open;
  for (int s = 0; s < 3; ++s) {
    auto stream = client_->OpenSession(Config(1));
    ASSERT_TRUE(stream.ok()) << stream.status();
    open.push_back(*std::move(stream));
  }
  auto fourth = client_->OpenSession(Config(1));
  ASSERT_FALSE(fourth.ok());
  EXPECT_EQ(fourth.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(fourth.status().message()), HasSubstr("max_sessions"));
  ASSERT_TRUE(open.back()->Close().ok());
  open.pop_back();
  auto again = client_->OpenSession(Config(1));
  EXPECT_TRUE(again.ok()) << again.status();
}

TEST_F(SimulationServerTest, TwoConcurrentSessions) {
  auto run = [&](uint64_t seed, std::vector<float>* rewards) {
    auto stream = client_->OpenSession(Config(4, seed));
    ASSERT_TRUE(stream.ok());
    std::vector<float> zeros(4 * 69, 0.f), reward;
    for (int s = 0; s < 20; ++s) {
      ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
      ASSERT_TRUE(DecodeFloatTensor((*stream)->result().reward(), "reward", &reward).ok());
      rewards->insert(rewards->end(), reward.begin(), reward.end());
    }
    ASSERT_TRUE((*stream)->Close().ok());
  };
  std::vector<float> a, b, a_alone;
  std::thread first([&] { run(5, &a); });
  std::thread second([&] { run(6, &b); });
  first.join();
  second.join();
  run(5, &a_alone);
  EXPECT_EQ(a.size(), 80u);
  EXPECT_EQ(a, a_alone);  // sessions do not disturb each other
  EXPECT_NE(a, b);
  auto stats = client_->GetStats();
  ASSERT_TRUE(stats.ok());
  EXPECT_EQ(stats->sessions_opened(), 3);
  EXPECT_EQ(stats->env_steps(), 3 * 20 * 4);
  EXPECT_EQ(stats->active_sessions(), 0);
}

// The body of the child process below: opens a session and steps until it is killed.
TEST(ChildProcess, DISABLED_ClientThatNeverLeaves) {
  const char* port = std::getenv("MODSKILL_TEST_PORT");
  ASSERT_NE(port, nullptr);
  ClientOptions options;
  options.server = absl::StrCat("127.0.0.1:", port);
  auto client = SimulationClient::Connect(options);
  ASSERT_TRUE(client.ok());
  auto stream = (*client)->OpenSession(Config(2));
  ASSERT_TRUE(stream.ok());
  std::vector<float> zeros(2 * 69, 0.f);
  std::printf("session open\n");
  std::fflush(stdout);
  while ((*stream)->Step(zeros.data()).ok()) {
  }
}

int ActiveSessions(SimulationClient& client) {
  auto stats = client.GetStats();
  return stats.ok() ? stats->active_sessions() : -1;
}

TEST_F(SimulationServerTest, ClientKilledMidStreamFreesItsEnvs) {
  const std::string port = std::to_string(server_->port());
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    setenv("MODSKILL_TEST_PORT", port.c_str(), 1);
    execl("/proc/self/exe", "simulation_server_test", "--gtest_also_run_disabled_tests",
          "--gtest_filter=ChildProcess.DISABLED_ClientThatNeverLeaves", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the child's session runs, then kill it without warning.
  const absl::Time deadline = absl::Now() + absl::Seconds(20);
  while (ActiveSessions(*client_) < 1 && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
  ASSERT_EQ(ActiveSessions(*client_), 1);
  auto stats = client_->GetStats();
  ASSERT_TRUE(stats.ok());
  ASSERT_EQ(stats->sessions_size(), 1);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  const absl::Time killed = absl::Now();
  while (ActiveSessions(*client_) != 0 && absl::Now() - killed < absl::Seconds(5)) absl::SleepFor(absl::Milliseconds(20));
  EXPECT_EQ(ActiveSessions(*client_), 0) << "a killed client's session must be freed within a few seconds";
  EXPECT_LT(absl::Now() - killed, absl::Seconds(5));
  // And the server still serves.
  auto stream = client_->OpenSession(Config(1));
  EXPECT_TRUE(stream.ok());
}

TEST_F(SimulationServerTest, CancelledStreamFreesItsEnvs) {
  auto stream = client_->OpenSession(Config(2));
  ASSERT_TRUE(stream.ok());
  ASSERT_EQ(ActiveSessions(*client_), 1);
  (*stream)->Cancel();
  const absl::Time start = absl::Now();
  while (ActiveSessions(*client_) != 0 && absl::Now() - start < absl::Seconds(5)) absl::SleepFor(absl::Milliseconds(10));
  EXPECT_EQ(ActiveSessions(*client_), 0);
}

TEST_F(SimulationServerTest, ReportFailuresValidatesAndStores) {
  v1::SessionConfig config = Config(2);
  config.add_motions("deepmimic_walk");
  config.add_motions("deepmimic_run");
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  v1::ReportFailuresRequest request;
  request.set_session_id((*stream)->opened().session_id());
  v1::ClipFailure* failure = request.add_failures();
  failure->set_clip("deepmimic_run");
  failure->set_frame(7);
  failure->set_terminated(true);
  for (float e : {0.1f, 0.2f, 0.3f, 0.05f, 0.05f}) failure->add_part_errors(e);
  v1::ClipFailure* success = request.add_failures();
  success->set_clip("deepmimic_walk");
  success->set_frame(-1);
  auto state = client_->ReportFailures(request);
  ASSERT_TRUE(state.ok()) << state.status();
  ASSERT_EQ(state->clips_size(), 2);
  EXPECT_EQ(state->clips(1).clip(), "deepmimic_run");
  EXPECT_EQ(state->clips(1).failures(), 1);
  EXPECT_EQ(state->clips(1).last_failed_frame(), 7);
  EXPECT_NEAR(state->clips(1).mean_part_errors(2), 0.3f, 1e-6);
  EXPECT_EQ(state->clips(0).successes(), 1);
  EXPECT_NEAR(state->clips(0).probability() + state->clips(1).probability(), 1.0, 1e-9);
  EXPECT_EQ(state->reports(), 2);

  auto expect = [&](v1::ReportFailuresRequest bad, absl::StatusCode code, const std::string& needle) {
    auto result = client_->ReportFailures(bad);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), code) << result.status();
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  };
  v1::ReportFailuresRequest bad = request;
  bad.set_session_id("s999");
  expect(bad, absl::StatusCode::kNotFound, "session_id");
  bad = request;
  bad.mutable_failures(1)->set_clip("deepmimic_backflip");  // in the library, not in the session
  expect(bad, absl::StatusCode::kNotFound, "failures[1].clip");
  bad = request;
  bad.mutable_failures(0)->add_part_errors(0.1f);
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].part_errors");
  bad = request;
  bad.mutable_failures(0)->set_part_errors(1, std::nanf(""));
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].part_errors[1]");
  bad = request;
  bad.mutable_failures(0)->set_frame(100000);
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].frame");
  // Rejected reports recorded nothing.
  auto unchanged = client_->ReportFailures(request);
  ASSERT_TRUE(unchanged.ok());
  EXPECT_EQ(unchanged->clips(1).failures(), 2);
  EXPECT_EQ(unchanged->reports(), 4);
}

std::vector<int32_t> Int32s(const v1::Tensor& tensor) {
  std::vector<int32_t> values(tensor.data().size() / sizeof(int32_t));
  std::memcpy(values.data(), tensor.data().data(), values.size() * sizeof(int32_t));
  return values;
}

const v1::SessionStats* FindSession(const v1::ServerStats& stats, const std::string& id) {
  for (const v1::SessionStats& session : stats.sessions()) {
    if (session.session_id() == id) return &session;
  }
  return nullptr;
}

// Adaptive sampling end to end: failures of one clip raise its probability in the reply and in
// GetStats, and the session's envs then start their episodes on it far more often.
TEST_F(SimulationServerTest, ReportedFailuresSteerWhichClipsEnvsStartOn) {
  const int n = 64;
  auto stream = client_->OpenSession(Config(n, 11));
  ASSERT_TRUE(stream.ok()) << stream.status();
  const v1::SessionOpened& opened = (*stream)->opened();
  const int num_clips = opened.clip_names_size();
  ASSERT_GE(num_clips, 10);
  const int target = 3;
  const std::string target_name = opened.clip_names(target);

  v1::ReportFailuresRequest request;
  request.set_session_id(opened.session_id());
  for (int k = 0; k < 50; ++k) {
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip(target_name);
    failure->set_frame(-1);
    failure->set_terminated(true);
  }
  v1::ClipFailure* success = request.add_failures();  // a success elsewhere changes little
  success->set_clip(opened.clip_names(0));
  success->set_frame(-1);
  auto state = client_->ReportFailures(request);
  ASSERT_TRUE(state.ok()) << state.status();
  ASSERT_EQ(state->clips_size(), num_clips);
  double total = 0;
  for (int c = 0; c < num_clips; ++c) {
    total += state->clips(c).probability();
    EXPECT_GE(state->clips(c).probability(), kDefaultSamplingFloor / num_clips * (1 - 1e-9)) << c;
  }
  EXPECT_NEAR(total, 1.0, 1e-9);
  EXPECT_EQ(state->clips(target).clip(), target_name);
  EXPECT_EQ(state->clips(target).failures(), 50);
  EXPECT_NEAR(state->clips(target).weight(), 50 + kFailureCountEpsilon, 1e-9);
  // Default floor 0.2: the failing clip takes the 80 % that follows the failures.
  EXPECT_NEAR(state->clips(target).probability(), 1 - (num_clips - 1) * kDefaultSamplingFloor / num_clips, 1e-6);

  auto stats = client_->GetStats();
  ASSERT_TRUE(stats.ok());
  const v1::SessionStats* session = FindSession(*stats, opened.session_id());
  ASSERT_NE(session, nullptr);
  ASSERT_EQ(session->clips_size(), num_clips);
  for (int c = 0; c < num_clips; ++c) {
    EXPECT_EQ(session->clips(c).clip(), opened.clip_names(c));
    EXPECT_DOUBLE_EQ(session->clips(c).probability(), state->clips(c).probability());
  }
  EXPECT_EQ(session->clips(target).failures(), 50);
  EXPECT_EQ(session->clips(0).successes(), 1);

  // Zero actions: the humanoids fall within a few dozen steps and restart on a drawn clip.
  std::vector<float> zeros(static_cast<size_t>(n) * 69, 0.f);
  int starts = 0, target_starts = 0;
  for (int s = 0; s < 50; ++s) {
    ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
    const v1::StepResult& result = (*stream)->result();
    const std::string& done = result.done().data();
    const std::vector<int32_t> clip_id = Int32s(result.clip_id());
    ASSERT_EQ(clip_id.size(), static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      if (!done[i]) continue;
      ++starts;
      target_starts += clip_id[i] == target;
    }
  }
  ASSERT_GE(starts, 500);
  const double share = static_cast<double>(target_starts) / starts;
  EXPECT_GT(share, 0.5) << target_starts << " of " << starts << " episodes (uniform: " << 1.0 / num_clips << ")";
  // Every restart is a fresh draw: the share estimates the reported probability (sd ~0.012 here).
  EXPECT_NEAR(share, state->clips(target).probability(), 0.06);
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST_F(SimulationServerTest, SuccessesBringTheProbabilityBack) {
  v1::SessionConfig config = Config(2);
  for (const char* clip : {"deepmimic_walk", "deepmimic_run", "deepmimic_jog", "deepmimic_kick"}) config.add_motions(clip);
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  auto report = [&](bool terminated, int times) {
    v1::ReportFailuresRequest request;
    request.set_session_id((*stream)->opened().session_id());
    for (int k = 0; k < times; ++k) {
      v1::ClipFailure* failure = request.add_failures();
      failure->set_clip("deepmimic_kick");
      failure->set_frame(-1);
      failure->set_terminated(terminated);
    }
    auto state = client_->ReportFailures(request);
    EXPECT_TRUE(state.ok()) << state.status();
    return state.ok() ? state->clips(3).probability() : -1.0;
  };
  // Count 5 against ε for the others: all but the floor (3 x 0.2 / 4) goes to the failing clip.
  const double failed = report(true, 5);
  EXPECT_NEAR(failed, 0.85, 1e-9);
  // 60 successes: count 5 x 0.9^60 = 0.009, close enough to the others' ε that they rise above the floor.
  const double recovering = report(false, 60);
  EXPECT_LT(recovering, failed - 0.05);
  EXPECT_NEAR(report(false, 200), 0.25, 1e-3);
  // Stepping applies the weights without disturbing the stream.
  std::vector<float> zeros(2 * 69, 0.f);
  for (int s = 0; s < 3; ++s) ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST(SimulationServerSamplingTest, UniformAblationNeverMovesAndDecaySchemeFollowsFailures) {
  for (SamplingScheme scheme : {SamplingScheme::kUniform, SamplingScheme::kDecayOnSuccess}) {
    ServerOptions options;
    options.service.sampling = scheme;
    auto server = StartTestServer(options);
    ASSERT_NE(server, nullptr);
    auto client = ConnectTo(*server);
    ASSERT_NE(client, nullptr);
    v1::SessionConfig config = Config(2);
    for (const char* clip : {"deepmimic_walk", "deepmimic_run", "deepmimic_jog"}) config.add_motions(clip);
    auto stream = client->OpenSession(config);
    ASSERT_TRUE(stream.ok());
    v1::ReportFailuresRequest request;
    request.set_session_id((*stream)->opened().session_id());
    for (int k = 0; k < 20; ++k) {
      v1::ClipFailure* success = request.add_failures();
      success->set_clip(k % 2 ? "deepmimic_walk" : "deepmimic_jog");
      success->set_frame(-1);
    }
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip("deepmimic_run");
    failure->set_frame(3);
    failure->set_terminated(true);
    auto state = client->ReportFailures(request);
    ASSERT_TRUE(state.ok()) << state.status();
    std::vector<float> zeros(2 * 69, 0.f);
    ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
    auto stats = client->GetStats();
    ASSERT_TRUE(stats.ok());
    ASSERT_EQ(stats->sessions_size(), 1);
    ASSERT_EQ(stats->sessions(0).clips_size(), 3);
    for (int c = 0; c < 3; ++c) {
      const double p = state->clips(c).probability();
      EXPECT_DOUBLE_EQ(stats->sessions(0).clips(c).probability(), p);
      if (scheme == SamplingScheme::kUniform) {
        EXPECT_DOUBLE_EQ(p, 1.0 / 3) << c;
        EXPECT_DOUBLE_EQ(state->clips(c).weight(), 1.0);
      }
    }
    if (scheme == SamplingScheme::kDecayOnSuccess) {
      EXPECT_DOUBLE_EQ(state->clips(1).weight(), 1.0);
      EXPECT_NEAR(state->clips(0).weight(), std::pow(0.999, 10), 1e-12);
      EXPECT_GT(state->clips(1).probability(), state->clips(0).probability());
    }
    EXPECT_EQ(state->clips(1).failures(), 1);
    EXPECT_TRUE((*stream)->Close().ok());
    server->Shutdown(absl::Seconds(1));
  }
}

TEST_F(SimulationServerTest, StepResultsCarryPerPartErrors) {
  for (const std::string layout : {"5part", "3part"}) {
    const int n = 4;
    v1::SessionConfig config = Config(n, 2);
    config.set_part_layout(layout);
    auto stream = client_->OpenSession(config);
    ASSERT_TRUE(stream.ok()) << stream.status();
    const v1::EnvSpec& spec = (*stream)->spec();
    const int parts = spec.parts_size();
    const v1::Tensor& initial = (*stream)->opened().initial().part_error();
    ASSERT_EQ(initial.shape_size(), 2);
    EXPECT_EQ(initial.shape(0), n);
    EXPECT_EQ(initial.shape(1), parts);
    EXPECT_EQ(initial.dtype(), v1::FLOAT32);
    std::vector<float> errors;
    ASSERT_TRUE(DecodeFloatTensor(initial, "part_error", &errors).ok());
    ASSERT_EQ(errors.size(), static_cast<size_t>(n) * parts);
    for (float e : errors) EXPECT_EQ(e, 0.f);  // reset onto the reference
    std::vector<float> zeros(static_cast<size_t>(n) * 69, 0.f), mean;
    for (int s = 0; s < 3; ++s) {
      ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
      const v1::StepResult& result = (*stream)->result();
      ASSERT_EQ(result.part_error().shape(1), parts);
      ASSERT_TRUE(DecodeFloatTensor(result.part_error(), "part_error", &errors).ok());
      ASSERT_TRUE(DecodeFloatTensor(result.mean_body_error(), "mean_body_error", &mean).ok());
      for (int i = 0; i < n; ++i) {
        // Part means weighted by their body counts give the whole-body mean.
        double weighted = 0;
        for (int p = 0; p < parts; ++p) {
          const float e = errors[static_cast<size_t>(i) * parts + p];
          EXPECT_GT(e, 0.f) << layout << " step " << s << " env " << i << " part " << p;
          EXPECT_LT(e, 1.f);
          weighted += e * spec.parts(p).bodies_size();
        }
        EXPECT_NEAR(weighted / spec.body_names_size(), mean[i], 1e-5) << layout << " env " << i;
      }
    }
    EXPECT_TRUE((*stream)->Close().ok());
  }
}

TEST_F(SimulationServerTest, SampleReferenceAmpMatchesTheResetHistories) {
  v1::SessionConfig config = Config(2);
  config.add_motions("deepmimic_walk");
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  v1::SampleReferenceAmpRequest request;
  request.set_session_id((*stream)->opened().session_id());
  request.set_num_samples(50);
  request.set_seed(3);
  auto samples = client_->SampleReferenceAmp(request);
  ASSERT_TRUE(samples.ok()) << samples.status();
  ASSERT_EQ(samples->amp_obs().shape(0), 50);
  ASSERT_EQ(samples->amp_obs().shape(1), 2320);
  std::vector<float> values;
  ASSERT_TRUE(DecodeFloatTensor(samples->amp_obs(), "amp_obs", &values).ok());
  // Each sample is a reference history: the initial AMP rows of the session are too, and the
  // root height (feature 0) of every frame lies in the walk clip's range.
  const MotionClip& walk = DefaultMotions()->clip(DefaultMotions()->Find("deepmimic_walk"));
  double low = 1e9, high = -1e9;
  for (int f = 0; f < walk.num_frames; ++f) {
    low = std::min(low, walk.body_pos[f * 24].z());
    high = std::max(high, walk.body_pos[f * 24].z());
  }
  for (int s = 0; s < 50; ++s) {
    for (int k = 0; k < 10; ++k) {
      const float height = values[s * 2320 + k * 232];
      EXPECT_GE(height, low - 1e-4);
      EXPECT_LE(height, high + 1e-4);
    }
  }
  request.set_num_samples(0);
  auto zero = client_->SampleReferenceAmp(request);
  ASSERT_FALSE(zero.ok());
  EXPECT_THAT(std::string(zero.status().message()), HasSubstr("num_samples"));
  request.set_num_samples(10);
  request.set_session_id("nope");
  EXPECT_EQ(client_->SampleReferenceAmp(request).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(SimulationServerTest, RolloutRunsATorchScriptCheckpoint) {
  v1::RolloutRequest request;
  request.set_checkpoint_path(ZeroPolicy());
  request.add_clips("deepmimic_walk");
  request.add_clips("cmu_02_01");
  request.set_stream_frames(true);
  int frames = 0;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) {
    ++frames;
    EXPECT_EQ(frame.sim_body_pos().shape(0), 24);
    EXPECT_EQ(frame.ref_body_pos().data().size(), 24u * 3 * 4);
  });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_EQ(metrics->size(), 2u);
  int steps = 0;
  for (const v1::ClipMetrics& clip : *metrics) {
    steps += clip.steps() + 1;
    EXPECT_GT(clip.g_mpjpe_mm(), 0);
    EXPECT_GE(clip.g_mpjpe_mm(), 0.5 * clip.mpjpe_mm());
    EXPECT_EQ(clip.body_error_mm_size(), 24);
    EXPECT_EQ(clip.part_error_mm_size(), 5);
    EXPECT_GT(clip.max_mean_body_error_m(), 0.0);
    // Evaluation termination: a failed clip went past 0.5 m mean error, a successful one never did.
    EXPECT_EQ(clip.success(), clip.max_mean_body_error_m() <= 0.5);
  }
  EXPECT_EQ(frames, steps);
  // The zero policy holds joints at their range midpoints: it falls, so it fails.
  EXPECT_FALSE((*metrics)[0].success());
  // The same checkpoint as bytes.
  v1::RolloutRequest by_bytes;
  by_bytes.set_checkpoint_bytes(*ReadFileToString(ZeroPolicy(), 1 << 30));
  by_bytes.add_clips("deepmimic_walk");
  auto again = client_->Rollout(by_bytes);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ((*again)[0].steps(), (*metrics)[0].steps());
  EXPECT_DOUBLE_EQ((*again)[0].g_mpjpe_mm(), (*metrics)[0].g_mpjpe_mm());
}

TEST_F(SimulationServerTest, RolloutBadInputs) {
  auto expect = [&](const v1::RolloutRequest& request, absl::StatusCode code, const std::string& needle) {
    auto result = client_->Rollout(request);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), code) << result.status();
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  };
  v1::RolloutRequest request;
  expect(request, absl::StatusCode::kInvalidArgument, "checkpoint");
  request.set_checkpoint_path(TempDir() + "/missing.pt");
  expect(request, absl::StatusCode::kNotFound, "checkpoint_path");
  const std::string garbage = TempDir() + "/garbage.pt";
  ASSERT_TRUE(WriteFileAtomically(garbage, "this is not a zip archive").ok());
  request.set_checkpoint_path(garbage);
  expect(request, absl::StatusCode::kInvalidArgument, "TorchScript");
  request.set_checkpoint_bytes(std::string(1000, 'x'));
  expect(request, absl::StatusCode::kInvalidArgument, "TorchScript");
  request.set_checkpoint_path(ZeroPolicy("3part"));  // trained with another layout: fine, the server offers it
  request.add_clips("deepmimic_walk");
  EXPECT_TRUE(client_->Rollout(request).ok());
  // A checkpoint for another observation size.
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  PolicySpec other = PolicySpec::FromEnvSpec(MakeEnvSpec(**humanoid, *catalog->Get("5part")));
  other.obs_size = 100;
  const std::string mismatched = TempDir() + "/mismatched.pt";
  ASSERT_TRUE(SaveAffinePolicy(mismatched, other, {}, {}).ok());
  request.set_checkpoint_path(mismatched);
  expect(request, absl::StatusCode::kFailedPrecondition, "obs_size");
  request.set_checkpoint_path(ZeroPolicy());
  request.add_clips("not_a_clip");
  expect(request, absl::StatusCode::kNotFound, "clips[1]");
  // A checkpoint runs in the action mode it was trained in; insisting on another is refused.
  request.clear_clips();
  request.add_clips("deepmimic_walk");
  request.set_action_mode(v1::RESIDUAL);
  expect(request, absl::StatusCode::kFailedPrecondition, "action_mode");
  request.set_action_mode(static_cast<v1::ActionMode>(12));
  expect(request, absl::StatusCode::kInvalidArgument, "action_mode");
  request.set_action_mode(v1::ABSOLUTE);
  EXPECT_TRUE(client_->Rollout(request).ok());
}

// The zero residual policy is open-loop reference tracking: it runs in residual mode (recorded in
// the checkpoint) and tracks the pose far better than the zero absolute policy, which holds every
// joint at its range midpoint.
TEST_F(SimulationServerTest, RolloutRunsAPolicyInItsTrainedActionMode) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  PolicySpec residual = PolicySpec::FromEnvSpec(MakeEnvSpec(**humanoid, *catalog->Get("5part")));
  residual.action = ActionMapping{ActionMode::kResidual, 0.5};
  auto bytes = AffinePolicyBytes(residual, {}, {});
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(*bytes);
  request.add_clips("deepmimic_walk");
  auto open_loop = client_->Rollout(request);
  ASSERT_TRUE(open_loop.ok()) << open_loop.status();
  request.set_action_mode(v1::ABSOLUTE);
  auto refused = client_->Rollout(request);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("residual"));
  v1::RolloutRequest absolute;
  absolute.set_checkpoint_path(ZeroPolicy());
  absolute.add_clips("deepmimic_walk");
  auto falls = client_->Rollout(absolute);
  ASSERT_TRUE(falls.ok()) << falls.status();
  // (Under evaluation termination the collapse takes a second either way; the pose error tells.)
  EXPECT_LT((*open_loop)[0].mpjpe_mm(), 0.75 * (*falls)[0].mpjpe_mm());
}

// Checkpoints from before action modes carry no action_mode: they were trained in absolute mode.
TEST(PolicySpecTest, OldSpecsLoadAsAbsoluteAndBadModesAreRefused) {
  const std::string old_json =
      R"({"part_layout": "5part", "obs_size": 934, "action_size": 69, "joint_names": [], "control_dt": 0.0333})";
  auto old_spec = PolicySpec::FromJson(old_json);
  ASSERT_TRUE(old_spec.ok()) << old_spec.status();
  EXPECT_EQ(old_spec->action.mode, ActionMode::kAbsolute);
  PolicySpec residual = *old_spec;
  residual.action = ActionMapping{ActionMode::kResidual, 0.25};
  auto round_trip = PolicySpec::FromJson(residual.ToJson());
  ASSERT_TRUE(round_trip.ok());
  EXPECT_EQ(round_trip->action.mode, ActionMode::kResidual);
  EXPECT_DOUBLE_EQ(round_trip->action.residual_scale, 0.25);
  std::string bad = residual.ToJson();
  bad.replace(bad.find("residual\""), 9, "sideways\"");
  auto refused = PolicySpec::FromJson(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("action_mode"));
  // Sizes are checked as written: 2^40 is reported as such, not as 0 after a cast.
  std::string huge = old_json;
  huge.replace(huge.find("934"), 3, "1099511627776");
  auto too_big = PolicySpec::FromJson(huge);
  ASSERT_FALSE(too_big.ok());
  EXPECT_THAT(std::string(too_big.status().message()), HasSubstr("obs_size: 1099511627776"));
  std::string fractional = old_json;
  fractional.replace(fractional.find("69"), 2, "69.5");
  EXPECT_FALSE(PolicySpec::FromJson(fractional).ok());
}

TEST_F(SimulationServerTest, AddMotionsUploadsAndValidates) {
  auto walk = ReadFileToString(std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt", 1 << 20);
  ASSERT_TRUE(walk.ok());
  v1::AddMotionsRequest request;
  v1::MotionUpload* upload = request.add_uploads();
  upload->set_file_name("humanoid3d_walk.txt");
  upload->set_data(*walk);
  upload->set_name("uploaded_walk");
  upload->set_label("a person walks (uploaded)");
  auto added = client_->AddMotions(request);
  ASSERT_TRUE(added.ok()) << added.status();
  ASSERT_EQ(added->added_size(), 1);
  EXPECT_EQ(added->added(0).name(), "uploaded_walk");
  auto listed = client_->ListMotions();
  ASSERT_TRUE(listed.ok());
  EXPECT_EQ(listed->motions_size(), DefaultMotions()->size() + 1);
  v1::SessionConfig config = Config(1);
  config.add_motions("uploaded_walk");
  EXPECT_TRUE(client_->OpenSession(config).ok());
  // The same name again is rejected, and nothing changes.
  auto duplicate = client_->AddMotions(request);
  ASSERT_FALSE(duplicate.ok());
  EXPECT_EQ(duplicate.status().code(), absl::StatusCode::kAlreadyExists);
  // Corrupt content names the upload.
  v1::AddMotionsRequest corrupt;
  corrupt.add_uploads()->set_file_name("broken.npz");
  corrupt.mutable_uploads(0)->set_data("PK\x03\x04 not really");
  auto broken = client_->AddMotions(corrupt);
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(broken.status().code(), absl::StatusCode::kInvalidArgument) << broken.status();
  EXPECT_THAT(std::string(broken.status().message()), HasSubstr("broken.npz"));
  EXPECT_THAT(std::string(broken.status().message()), ::testing::Not(HasSubstr("modskill-upload")));
  v1::AddMotionsRequest unknown;
  unknown.add_uploads()->set_file_name("clip.fbx");
  unknown.mutable_uploads(0)->set_data("xyz");
  auto fbx = client_->AddMotions(unknown);
  ASSERT_FALSE(fbx.ok());
  EXPECT_THAT(std::string(fbx.status().message()), HasSubstr(".fbx"));
  v1::AddMotionsRequest oversized;
  oversized.add_uploads()->set_file_name("big.txt");
  oversized.mutable_uploads(0)->set_data(std::string((1 << 20) + 1, ' '));
  auto big = client_->AddMotions(oversized);
  ASSERT_FALSE(big.ok());
  EXPECT_EQ(big.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(big.status().message()), HasSubstr("max_upload_mb"));
  v1::AddMotionsRequest sneaky;
  sneaky.add_uploads()->set_file_name("../../etc/passwd.txt");
  sneaky.mutable_uploads(0)->set_data(*walk);
  auto traversal = client_->AddMotions(sneaky);
  ASSERT_TRUE(traversal.ok()) << traversal.status();  // stored under its base name only
  EXPECT_EQ(traversal->added(0).name(), "passwd");
  auto empty = client_->AddMotions(v1::AddMotionsRequest());
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(SimulationServerAuthTest, TokenIsRequiredWhenConfigured) {
  ServerOptions options;
  options.service.auth_token = "s3cret-token";
  auto server = StartTestServer(options);
  ASSERT_NE(server, nullptr);
  for (const std::string& token : {std::string(), std::string("wrong-token")}) {
    auto client = ConnectTo(*server, token);
    ASSERT_NE(client, nullptr);
    auto spec = client->Describe();
    ASSERT_FALSE(spec.ok());
    EXPECT_EQ(spec.status().code(), absl::StatusCode::kUnauthenticated);
    auto stream = client->OpenSession(Config(1));
    ASSERT_FALSE(stream.ok());
    EXPECT_EQ(stream.status().code(), absl::StatusCode::kUnauthenticated);
    EXPECT_EQ(client->GetStats().status().code(), absl::StatusCode::kUnauthenticated);
    EXPECT_EQ(client->ListMotions().status().code(), absl::StatusCode::kUnauthenticated);
  }
  auto good = ConnectTo(*server, "s3cret-token");
  EXPECT_TRUE(good->Describe().ok());
  auto stream = good->OpenSession(Config(1));
  ASSERT_TRUE(stream.ok());
  std::vector<float> zeros(69, 0.f);
  EXPECT_TRUE((*stream)->Step(zeros.data()).ok());
  // Without a configured token, no header is needed.
  auto open = StartTestServer();
  EXPECT_TRUE(ConnectTo(*open)->Describe().ok());
}

}  // namespace
}  // namespace modskill
