// The gRPC server end to end: the contract, equality with the in-process core, every bad
// input answered with the right status, concurrent and vanishing clients, uploads, auth.
// Sampling and AMP: sampling_server_test.cc; rollouts: rollout_server_test.cc.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <thread>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/wire/tensor_codec.h"
#include "tests/server_fixture.h"
#include "tests/simulation_server_fixture.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

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
  ASSERT_TRUE(ReadFloatTensor((*stream)->opened().initial().obs(), "obs", &obs).ok());
  ASSERT_EQ(obs, local->buffers().obs);
  EXPECT_EQ((*stream)->opened().clip_names_size(), DefaultMotions()->size());
  for (int s = 0; s < 12; ++s) {
    const std::vector<float> actions = ReferenceActions(*local);
    ASSERT_TRUE(local->Step(actions).ok());
    ASSERT_TRUE((*stream)->Step(actions.data()).ok());
    const v1::StepResult& result = (*stream)->result();
    EXPECT_EQ(result.step(), s + 1);
    std::vector<float> remote;
    ASSERT_TRUE(ReadFloatTensor(result.obs(), "obs", &remote).ok());
    ASSERT_EQ(remote, local->buffers().obs) << s;
    ASSERT_TRUE(ReadFloatTensor(result.reward(), "reward", &remote).ok());
    ASSERT_EQ(remote, local->buffers().reward) << s;
    ASSERT_TRUE(ReadFloatTensor(result.amp_obs(), "amp_obs", &remote).ok());
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
  for (float weight : {-0.5f, std::nanf(""), std::numeric_limits<float>::infinity(), 100.5f}) {
    config = Config(2);
    config.set_energy_weight(weight);
    cases.push_back({config, absl::StatusCode::kInvalidArgument, "energy_weight"});
  }
  for (float k : {-1.f, std::nanf(""), std::numeric_limits<float>::infinity(), 10001.f}) {
    config = Config(2);
    config.mutable_imitation_kernels()->set_rot(k);
    cases.push_back({config, absl::StatusCode::kInvalidArgument, "imitation_kernels.rot"});
  }
  config = Config(2);
  config.set_task("reach");
  config.mutable_imitation_kernels()->set_pos(400);
  cases.push_back({config, absl::StatusCode::kInvalidArgument, "imitation_kernels: task reach"});
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

// Six steps of zero actions in 4 envs of `config` (no termination, so that no row resets):
// every step's reward_terms and reward, appended.
void StepZeroActions(SimulationClient& client, v1::SessionConfig config, std::vector<float>* terms,
                     std::vector<float>* rewards) {
  config.set_termination(v1::NONE);
  auto stream = client.OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  std::vector<float> zeros(4 * 69, 0.f), step_terms, reward;
  for (int s = 0; s < 6; ++s) {
    ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
    ASSERT_TRUE(ReadFloatTensor((*stream)->result().reward_terms(), "reward_terms", &step_terms).ok());
    ASSERT_TRUE(ReadFloatTensor((*stream)->result().reward(), "reward", &reward).ok());
    terms->insert(terms->end(), step_terms.begin(), step_terms.end());
    rewards->insert(rewards->end(), reward.begin(), reward.end());
  }
  ASSERT_TRUE((*stream)->Close().ok());
}

// SessionConfig.energy_weight scales the energy column (and so the reward) and nothing else.
TEST_F(SimulationServerTest, EnergyWeightScalesTheEnergyTerm) {
  auto run = [&](std::optional<float> weight, std::vector<float>* terms, std::vector<float>* rewards) {
    v1::SessionConfig config = Config(4, 9);
    if (weight) config.set_energy_weight(*weight);
    StepZeroActions(*client_, config, terms, rewards);
  };
  std::vector<float> paper, paper_reward, doubled, doubled_reward, off, off_reward;
  run(std::nullopt, &paper, &paper_reward);
  ASSERT_FALSE(paper_reward.empty());
  run(2.f, &doubled, &doubled_reward);
  run(0.f, &off, &off_reward);
  const size_t columns = paper.size() / paper_reward.size();
  ASSERT_EQ(columns, 5u);  // pos, rot, vel, ang_vel, energy
  double paper_energy = 0;
  for (size_t row = 0; row < paper_reward.size(); ++row) {
    const size_t energy = row * columns + columns - 1;
    paper_energy += paper[energy];
    EXPECT_NEAR(doubled[energy], 2 * paper[energy], 1e-6 + 1e-5 * std::abs(paper[energy])) << row;
    EXPECT_EQ(off[energy], 0.f) << row;
    for (size_t c = 0; c + 1 < columns; ++c) EXPECT_EQ(off[row * columns + c], paper[row * columns + c]) << row;
    EXPECT_NEAR(off_reward[row], paper_reward[row] - paper[energy], 1e-5) << row;
    EXPECT_NEAR(doubled_reward[row], paper_reward[row] + paper[energy], 1e-5) << row;
  }
  EXPECT_LT(paper_energy, 0.0) << "zero actions spend power";
}

// SessionConfig.imitation_kernels: a term with k x 4 is w (term / w)^4 of the default's, for the
// same states; the other terms are untouched.
TEST_F(SimulationServerTest, ImitationKernelsSteepenTheirTerm) {
  std::vector<float> base, base_reward, steep, steep_reward;
  StepZeroActions(*client_, Config(4, 9), &base, &base_reward);
  v1::SessionConfig config = Config(4, 9);
  config.mutable_imitation_kernels()->set_pos(400);  // PHC's 100 x 4
  StepZeroActions(*client_, config, &steep, &steep_reward);
  ASSERT_FALSE(base_reward.empty());
  ASSERT_EQ(base.size(), steep.size());
  const size_t columns = base.size() / base_reward.size();
  const double w_pos = ImitationRewardConfig().w_pos;
  double base_sum = 0, steep_sum = 0;
  for (size_t row = 0; row < base_reward.size(); ++row) {
    const float pos = base[row * columns + kRewardPos];
    EXPECT_NEAR(steep[row * columns + kRewardPos], w_pos * std::pow(pos / w_pos, 4), 1e-5) << row;
    for (size_t c = 0; c < columns; ++c) {
      if (c != static_cast<size_t>(kRewardPos)) EXPECT_EQ(steep[row * columns + c], base[row * columns + c]) << row;
    }
    base_sum += pos;
    steep_sum += steep[row * columns + kRewardPos];
  }
  EXPECT_LT(steep_sum, base_sum - 1e-3) << "zero actions leave the reference: a steeper kernel pays less";
}

TEST_F(SimulationServerTest, TwoConcurrentSessions) {
  auto run = [&](uint64_t seed, std::vector<float>* rewards) {
    auto stream = client_->OpenSession(Config(4, seed));
    ASSERT_TRUE(stream.ok());
    std::vector<float> zeros(4 * 69, 0.f), reward;
    for (int s = 0; s < 20; ++s) {
      ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
      ASSERT_TRUE(ReadFloatTensor((*stream)->result().reward(), "reward", &reward).ok());
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
