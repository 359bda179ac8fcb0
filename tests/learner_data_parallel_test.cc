// Data-parallel learners (learner/data_parallel.h) as threads of this process meeting at a
// loopback rendezvous: flags are checked naming the flag; merged normalizer statistics are those
// of the concatenated data; a rank that never joins, or that dies, stops the others within a
// bounded time naming it; mismatched settings fail on every rank naming the setting; and two
// trainers, each on its own in-process server, end every iteration with bitwise-equal weights and
// statistics, write only from rank 0 and resume with the same world size only.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <future>
#include <vector>

#include <gmock/gmock.h>

#include "learner/data_parallel.h"
#include "learner/trainer.h"
#include "tests/server_fixture.h"
#include "tests/trainer_test_config.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

// A loopback port nobody listens on now (the kernel's next ephemeral one).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(address);
  EXPECT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
  EXPECT_EQ(getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length), 0);
  close(fd);
  return ntohs(address.sin_port);
}

DataParallelOptions Options(int world_size, int rank, int port, double timeout_s = 10) {
  DataParallelOptions options;
  options.world_size = world_size;
  options.rank = rank;
  options.rendezvous = absl::StrCat("127.0.0.1:", port);
  options.rendezvous_timeout_s = timeout_s;
  options.collective_timeout_s = timeout_s;
  return options;
}

// Runs `body(rank)` for every rank on its own thread and returns the ranks' results.
template <typename Result>
std::vector<Result> OnRanks(int world_size, const std::function<Result(int)>& body) {
  std::vector<std::future<Result>> ranks;
  for (int rank = 0; rank < world_size; ++rank) ranks.push_back(std::async(std::launch::async, body, rank));
  std::vector<Result> results;
  for (auto& rank : ranks) results.push_back(rank.get());
  return results;
}

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

TEST(DataParallelTest, FlagsAreCheckedNamingTheFlag) {
  EXPECT_TRUE(ValidateDataParallelOptions(DataParallelOptions()).ok());
  const std::pair<DataParallelOptions, std::string> bad[] = {
      {{0, 0, "", 60, 300}, "--world_size: 0 must be >= 1"},
      {{2, 2, "h:1", 60, 300}, "--rank: 2 is outside [0, --world_size 2)"},
      {{2, -1, "h:1", 60, 300}, "--rank: -1"},
      {{2, 1, "", 60, 300}, "--rendezvous: required"},
      {{2, 1, "rank0host", 60, 300}, "--rendezvous rank0host: not host:port"},
      {{2, 1, "h:0", 60, 300}, "--rendezvous h:0"},
      {{2, 1, "h:70000", 60, 300}, "--rendezvous h:70000"},
      {{2, 1, "h:1", 0, 300}, "--rendezvous_timeout_s"},
      {{2, 1, "h:1", 60, -1}, "--collective_timeout_s"},
  };
  for (const auto& [options, message] : bad) {
    const absl::Status status = ValidateDataParallelOptions(options);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << message;
    EXPECT_THAT(std::string(status.message()), HasSubstr(message));
  }
  // The trainer's config checks them before anything starts.
  TrainerConfig config = SmallTestTrainerConfig({"127.0.0.1:1"}, "/tmp/unused");
  config.data_parallel = {2, 3, "127.0.0.1:1", 60, 300};
  EXPECT_THAT(std::string(config.Validate().message()), HasSubstr("--rank: 3"));
  EXPECT_THAT(std::string(Trainer::Create(config).status().message()), HasSubstr("--rank: 3"));
}

TEST(DataParallelTest, MergedStatisticsAreThoseOfTheConcatenatedData) {
  const int port = FreePort();
  const torch::Tensor prior = torch::randn({7, 3}, torch::kFloat64) * 2 + 1;
  // Different sizes per rank, one rank without samples.
  const std::vector<torch::Tensor> batches = {torch::randn({5, 3}, torch::kFloat64) * 3 - 2,
                                              torch::zeros({0, 3}, torch::kFloat64),
                                              torch::randn({17, 3}, torch::kFloat64) + 4};
  const auto merged = OnRanks<RunningMeanStd>(3, [&](int rank) {
    RunningMeanStd stats(3);
    stats->Update(prior);
    auto group = DataParallel::Join(Options(3, rank, port));
    EXPECT_TRUE(group.ok()) << group.status();
    if (group.ok()) EXPECT_TRUE((*group)->MergeRunningStats(*stats, batches[rank]).ok());
    return stats;
  });
  const torch::Tensor all = torch::cat({prior, batches[0], batches[1], batches[2]});
  for (const RunningMeanStd& stats : merged) {
    EXPECT_EQ(stats->count().item<double>(), 29);
    EXPECT_TRUE(torch::allclose(stats->mean(), all.mean(0), 0, 1e-12)) << stats->mean() << all.mean(0);
    EXPECT_TRUE(torch::allclose(stats->var(), all.var(0, /*unbiased=*/false), 0, 1e-12));
    // Identical on every rank, to the last bit.
    EXPECT_TRUE(torch::equal(stats->mean(), merged[0]->mean()));
    EXPECT_TRUE(torch::equal(stats->var(), merged[0]->var()));
  }
}

TEST(DataParallelTest, GradientsAreAveragedAndANonFiniteLossSkipsEveryRank) {
  const int port = FreePort();
  const auto results = OnRanks<std::vector<torch::Tensor>>(2, [&](int rank) {
    auto group = DataParallel::Join(Options(2, rank, port));
    EXPECT_TRUE(group.ok()) << group.status();
    if (!group.ok()) return std::vector<torch::Tensor>{};
    torch::Tensor weight = torch::zeros({2, 2}, torch::requires_grad());
    weight.mutable_grad() = torch::full({2, 2}, rank == 0 ? 1.0f : 4.0f);
    EXPECT_TRUE(*(*group)->AverageGradients({weight}, true));
    const torch::Tensor averaged = weight.grad().clone();
    // Rank 1's loss was not finite: neither rank steps.
    EXPECT_FALSE(*(*group)->AverageGradients({weight}, rank == 0));
    EXPECT_GT((*group)->collective_bytes(), 0);
    return std::vector<torch::Tensor>{averaged};
  });
  for (const auto& result : results) {
    ASSERT_EQ(result.size(), 1u);
    EXPECT_TRUE(torch::equal(result[0], torch::full({2, 2}, 2.5f)));
  }
}

TEST(DataParallelTest, ARankThatNeverJoinsIsANamedErrorWithinTheTimeout) {
  const int port = FreePort();
  auto start = Clock::now();
  absl::StatusOr<std::unique_ptr<DataParallel>> alone = DataParallel::Join(Options(2, 0, port, 2));
  ASSERT_FALSE(alone.ok());
  EXPECT_EQ(alone.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(alone.status().message()), HasSubstr(absl::StrCat("--rendezvous 127.0.0.1:", port)));
  EXPECT_THAT(std::string(alone.status().message()), HasSubstr("rank(s) 1 of --world_size 2 did not reach"));
  EXPECT_LT(SecondsSince(start), 10);

  // No rank 0 at the address: the others name it.
  start = Clock::now();
  absl::StatusOr<std::unique_ptr<DataParallel>> orphan = DataParallel::Join(Options(2, 1, FreePort(), 2));
  ASSERT_FALSE(orphan.ok());
  EXPECT_THAT(std::string(orphan.status().message()), HasSubstr("cannot reach rank 0's store within 2 s"));
  EXPECT_LT(SecondsSince(start), 10);
}

TEST(DataParallelTest, ARankThatDiesStopsTheOthersNamingIt) {
  const int port = FreePort();
  const auto start = Clock::now();
  const auto results = OnRanks<absl::Status>(2, [&](int rank) {
    auto group = DataParallel::Join(Options(2, rank, port, 5));
    if (!group.ok()) return group.status();
    std::vector<double> values = {1};
    EXPECT_TRUE((*group)->AllReduceSum(&values).ok());
    EXPECT_EQ(values[0], 2);
    (*group)->MarkIteration(rank == 0 ? 4 : 3);
    if (rank == 1) {
      group->reset();  // rank 1 is gone before iteration 4's collectives
      return absl::OkStatus();
    }
    absl::SleepFor(absl::Milliseconds(200));
    return (*group)->AllReduceSum(&values);
  });
  ASSERT_FALSE(results[0].ok());
  const std::string message(results[0].message());
  EXPECT_THAT(message, HasSubstr("rank 1 stopped answering"));
  EXPECT_THAT(message, HasSubstr("--resume"));
  EXPECT_LT(SecondsSince(start), 20);
}

std::string RunDir(const std::string& name) {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/data_parallel/" + name;
  std::filesystem::remove_all(dir);
  return dir;
}

// Rank `rank` of `world_size` on its own server, writing (rank 0) into `dir`.
TrainerConfig RankConfig(int world_size, int rank, int rendezvous_port, int server_port, const std::string& dir) {
  TrainerConfig config = SmallTestTrainerConfig({absl::StrCat("127.0.0.1:", server_port)},
                                                rank == 0 ? dir : dir + "_rank" + std::to_string(rank));
  config.iterations = 3;
  config.data_parallel = Options(world_size, rank, rendezvous_port, 30);
  return config;
}

// Every trained tensor and normalizer statistic, copied.
std::vector<torch::Tensor> StateOf(Trainer& trainer) {
  std::vector<torch::Tensor> state;
  for (torch::nn::Module* module : std::initializer_list<torch::nn::Module*>{
           trainer.policy().get(), trainer.critic().get(), trainer.discriminator().get()}) {
    for (const torch::Tensor& p : module->parameters()) state.push_back(p.detach().clone());
  }
  for (RunningMeanStd* stats : {&trainer.obs_norm(), &trainer.amp_norm()}) {
    for (const torch::Tensor& b : (*stats)->buffers()) state.push_back(b.clone());
  }
  return state;
}

// One rank's run: its state after every iteration, and its figures.
struct RankRun {
  absl::Status status;
  std::vector<std::vector<torch::Tensor>> states;
  std::vector<IterationStats> history;
};

RankRun TrainRank(const TrainerConfig& config) {
  RankRun run;
  auto trainer = Trainer::Create(config);
  if (!trainer.ok()) return RankRun{trainer.status(), {}, {}};
  run.states.push_back(StateOf(**trainer));
  run.status = (*trainer)->Run([&](const IterationStats&) { run.states.push_back(StateOf(**trainer)); });
  run.history = (*trainer)->history();
  return run;
}

TEST(LearnerDataParallelTest, TwoRanksEndEveryIterationWithBitwiseEqualWeights) {
  std::unique_ptr<RunningServer> servers[] = {StartTestServer(), StartTestServer()};
  const std::string dir = RunDir("two_ranks");
  const int port = FreePort();
  const auto runs = OnRanks<RankRun>(
      2, [&](int rank) { return TrainRank(RankConfig(2, rank, port, servers[rank]->port(), dir)); });
  for (const RankRun& run : runs) ASSERT_TRUE(run.status.ok()) << run.status;
  ASSERT_EQ(runs[0].states.size(), 4u);  // the start and 3 iterations
  ASSERT_EQ(runs[1].states.size(), 4u);
  bool data_differed = false;
  for (size_t i = 0; i < runs[0].states.size(); ++i) {
    ASSERT_EQ(runs[0].states[i].size(), runs[1].states[i].size());
    for (size_t k = 0; k < runs[0].states[i].size(); ++k) {
      EXPECT_TRUE(torch::equal(runs[0].states[i][k], runs[1].states[i][k])) << "iteration " << i << ", tensor " << k;
    }
    if (i > 0) {
      // Training moved the weights, and the ranks learned from different experience.
      EXPECT_FALSE(torch::equal(runs[0].states[i][0], runs[0].states[i - 1][0])) << "iteration " << i;
      const IterationStats& a = runs[0].history[i - 1];
      const IterationStats& b = runs[1].history[i - 1];
      data_differed |= a.mean_task_reward != b.mean_task_reward;
      EXPECT_EQ(a.env_steps, static_cast<int64_t>(i) * 2 * 16 * 8);  // both ranks' steps
      EXPECT_EQ(a.env_steps, b.env_steps);
      EXPECT_EQ(a.termination_distance, b.termination_distance);
      EXPECT_GT(a.allreduce_bytes, 0);
    }
  }
  EXPECT_TRUE(data_differed);
  // Rank 0 alone wrote the run.
  EXPECT_TRUE(std::filesystem::exists(dir + "/checkpoint.pt"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/policy.pt"));
  EXPECT_FALSE(std::filesystem::exists(dir + "_rank1"));
}

TEST(LearnerDataParallelTest, RanksResumeFromRankZerosCheckpointWithTheSameWorldSizeOnly) {
  std::unique_ptr<RunningServer> servers[] = {StartTestServer(), StartTestServer()};
  const std::string dir = RunDir("resume");
  int port = FreePort();
  const auto first = OnRanks<RankRun>(2, [&](int rank) {
    TrainerConfig config = RankConfig(2, rank, port, servers[rank]->port(), dir);
    config.iterations = 1;
    return TrainRank(config);
  });
  for (const RankRun& run : first) ASSERT_TRUE(run.status.ok()) << run.status;
  port = FreePort();
  const auto resumed = OnRanks<RankRun>(2, [&](int rank) {
    TrainerConfig config = RankConfig(2, rank, port, servers[rank]->port(), dir);
    config.iterations = 1;
    config.resume = true;
    return TrainRank(config);
  });
  for (const RankRun& run : resumed) ASSERT_TRUE(run.status.ok()) << run.status;
  // Rank 1 has no checkpoint of its own: it started from rank 0's, at iteration 1.
  for (size_t k = 0; k < first[0].states.back().size(); ++k) {
    EXPECT_TRUE(torch::equal(resumed[1].states.front()[k], first[0].states.back()[k])) << "tensor " << k;
  }
  EXPECT_EQ(resumed[1].history.back().iteration, 2);

  // Alone, the run does not resume.
  TrainerConfig alone = RankConfig(1, 0, FreePort(), servers[0]->port(), dir);
  alone.data_parallel = DataParallelOptions();
  alone.resume = true;
  auto refused = Trainer::Create(alone);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("trained with --world_size 2"));
}

TEST(LearnerDataParallelTest, MismatchedSettingsAreANamedErrorOnEveryRank) {
  const int port = FreePort();
  const auto start = Clock::now();
  // No server is contacted before the ranks compare their settings.
  const std::string dir = RunDir("mismatch");
  const auto results = OnRanks<absl::Status>(2, [&](int rank) {
    TrainerConfig config = RankConfig(2, rank, port, 1, dir);
    if (rank == 1) config.action_mode = "absolute";
    return Trainer::Create(config).status();
  });
  for (const absl::Status& status : results) {
    EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
    EXPECT_THAT(std::string(status.message()), HasSubstr("--action_mode: rank 0 has residual, rank 1 has absolute"));
  }
  EXPECT_LT(SecondsSince(start), 20);
}

TEST(LearnerDataParallelTest, ARankThatFailsAtStartupIsNamedByTheOthers) {
  auto server = StartTestServer();
  const int port = FreePort();
  const std::string dir = RunDir("startup");
  const auto start = Clock::now();
  const auto results = OnRanks<absl::Status>(2, [&](int rank) {
    // Rank 1's server never answers: it gives up after its --server_timeout_s.
    TrainerConfig config = RankConfig(2, rank, port, rank == 0 ? server->port() : FreePort(), dir);
    config.server_timeout_s = 2;
    return Trainer::Create(config).status();
  });
  EXPECT_THAT(std::string(results[1].message()), HasSubstr("no simulation server answered"));
  EXPECT_THAT(std::string(results[0].message()), HasSubstr("rank 1 failed: no simulation server answered"));
  EXPECT_LT(SecondsSince(start), 20);
}

}  // namespace
}  // namespace modskill::learner
