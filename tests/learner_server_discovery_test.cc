// Server discovery for the learner: --servers entries (host:port, dns:///name:port, file:///path)
// parse or fail naming the entry; dns:///localhost resolves; a name that resolves to nothing is
// a clear error within a bounded time; a server file that gains and loses servers between
// iterations changes which in-process servers the trainer drives.
#include <filesystem>
#include <set>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "learner/address_resolver.h"
#include "learner/server_discovery.h"
#include "learner/trainer.h"
#include "tests/server_fixture.h"
#include "tests/trainer_test_config.h"

namespace modskill::learner {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

std::string TestDir(const std::string& name) {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/server_discovery/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The learner tests' config, cut to one short iteration: these tests watch membership, not learning.
TrainerConfig TinyConfig(const std::vector<std::string>& servers, const std::string& run_dir) {
  TrainerConfig config = SmallTestTrainerConfig(servers, run_dir);
  config.horizon = 4;
  config.epochs = 1;
  config.minibatch_size = 32;
  config.amp_samples = 32;
  config.iterations = 1;
  config.checkpoint_every = 100;
  return config;
}

// The distinct servers of the trainer's live sessions.
std::set<std::string> LiveServers(Trainer& trainer) {
  std::set<std::string> servers;
  for (SessionSlot* slot : trainer.servers().Alive()) servers.insert(slot->server);
  return servers;
}

TEST(ServerDiscoveryTest, EntriesParseOrAreClearErrors) {
  for (const std::string good : {"127.0.0.1:50051", "sim-node-1:50051", "[::1]:50051", "dns:///localhost:50051",
                                 "dns:///modskill-server.default.svc.cluster.local:50051", "file:///etc/servers.txt"}) {
    EXPECT_TRUE(ParseServerSource(good).ok()) << good << ": " << ParseServerSource(good).status();
  }
  EXPECT_EQ(ParseServerSource("dns:///localhost:50051")->kind, ServerSource::Kind::kDns);
  EXPECT_EQ(ParseServerSource("file:///etc/servers.txt")->path, "/etc/servers.txt");
  const std::pair<std::string, std::string> bad[] = {
      {"localhost", "host:port"},         {"dns:///localhost", "host:port"},
      {"host:0", "[1, 65535]"},           {"host:99999", "[1, 65535]"},
      {"dns://8.8.8.8/name:1", "dns:///"}, {"file://servers.txt", "file:///absolute/path"},
      {"http://host:1", "unknown scheme"}, {"ho st:1", "bad character"},
  };
  for (const auto& [entry, why] : bad) {
    absl::StatusOr<ServerSource> source = ParseServerSource(entry);
    ASSERT_FALSE(source.ok()) << entry;
    EXPECT_EQ(source.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(source.status().message()), HasSubstr("--servers " + entry + ": ")) << entry;
    EXPECT_THAT(std::string(source.status().message()), HasSubstr(why)) << entry;
  }
  TrainerConfig config = TinyConfig({"127.0.0.1:1", "dns://x/y:1"}, TestDir("bad_entry"));
  EXPECT_THAT(std::string(config.Validate().message()), HasSubstr("--servers dns://x/y:1"));
}

TEST(ServerDiscoveryTest, ServerFilesAreReadOrNamedInTheError) {
  const std::string dir = TestDir("files");
  ASSERT_TRUE(WriteFileAtomically(dir + "/ok.txt", "# the fleet\n\n  10.0.0.5:50051  # rack 1\n[::1]:7\n").ok());
  absl::StatusOr<ServerDiscovery> discovery = ServerDiscovery::Create({"file://" + dir + "/ok.txt"});
  ASSERT_TRUE(discovery.ok()) << discovery.status();
  std::vector<ServerMember> members = discovery->Refresh();
  ASSERT_EQ(members.size(), 2u);
  EXPECT_EQ(members[0].address, "10.0.0.5:50051");
  EXPECT_EQ(members[1].address, "[::1]:7");
  EXPECT_EQ(*FirstServerTarget({"file://" + dir + "/ok.txt"}), "10.0.0.5:50051");

  ASSERT_TRUE(WriteFileAtomically(dir + "/bad.txt", "10.0.0.5:50051\nnot an address\n").ok());
  absl::StatusOr<ServerDiscovery> bad = ServerDiscovery::Create({"file://" + dir + "/bad.txt"});
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr(dir + "/bad.txt:2: 'not an address'"));
  absl::StatusOr<ServerDiscovery> missing = ServerDiscovery::Create({"file://" + dir + "/missing.txt"});
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(std::string(missing.status().message()),
              HasSubstr("--servers file://" + dir + "/missing.txt: cannot read " + dir + "/missing.txt"));

  // A file that breaks during the run keeps the servers it listed last.
  ASSERT_TRUE(WriteFileAtomically(dir + "/ok.txt", "10.0.0.5:50051\n10.0.0.6:x\n").ok());
  EXPECT_EQ(discovery->Refresh().size(), 2u);
  ASSERT_EQ(discovery->problems().size(), 1u);
  EXPECT_THAT(discovery->problems()[0], HasSubstr("ok.txt:2: '10.0.0.6:x'"));
}

TEST(ServerDiscoveryTest, DnsLocalhostResolvesToOneMemberPerServer) {
  absl::StatusOr<std::vector<std::string>> addresses = ResolveTcpAddresses("localhost", 50051, absl::Seconds(5));
  ASSERT_TRUE(addresses.ok()) << addresses.status();
  EXPECT_THAT(*addresses, Contains("127.0.0.1:50051"));
  EXPECT_EQ(addresses->size(), 1u) << "IPv4 preferred: one session set per server, not one per family";

  auto server = StartTestServer();
  const std::string entry = absl::StrCat("dns:///localhost:", server->port());
  auto trainer = Trainer::Create(TinyConfig({entry}, TestDir("dns_localhost")));
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run().ok());
  EXPECT_EQ(LiveServers(**trainer), std::set<std::string>{absl::StrCat("127.0.0.1:", server->port())});
  EXPECT_EQ((*trainer)->history().back().live_sessions, 2);
  for (SessionSlot* slot : (*trainer)->servers().Alive()) EXPECT_EQ(slot->tls_server_name, "localhost");
  server->Shutdown(absl::Seconds(1));
}

TEST(ServerDiscoveryTest, ANameThatResolvesToNothingIsAQuickErrorNamingIt) {
  const std::string entry = "dns:///no-such-modskill-server.invalid:50051";  // .invalid never resolves (RFC 6761)
  absl::StatusOr<ServerDiscovery> discovery = ServerDiscovery::Create({entry});
  ASSERT_TRUE(discovery.ok()) << discovery.status();
  absl::Time start = absl::Now();
  EXPECT_TRUE(discovery->Refresh().empty());
  EXPECT_LT(absl::Now() - start, absl::Seconds(6)) << "bounded by DiscoveryOptions::resolve_timeout";
  ASSERT_EQ(discovery->problems().size(), 1u);
  EXPECT_THAT(discovery->problems()[0], HasSubstr("--servers " + entry + ": no-such-modskill-server.invalid"));

  TrainerConfig config = TinyConfig({entry}, TestDir("unresolvable"));
  config.server_timeout_s = 1;
  start = absl::Now();
  auto trainer = Trainer::Create(config);
  ASSERT_FALSE(trainer.ok());
  EXPECT_EQ(trainer.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr("no simulation server answered"));
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr(entry));
  EXPECT_LT(absl::Now() - start, absl::Seconds(15));
}

// The file lists A; after iteration 1 it lists A and B, after iteration 3 only B. Each change is
// used from the next iteration: B's sessions join, then A's are dropped.
TEST(ServerDiscoveryTest, AServerFileThatGainsAndLosesServersChangesThePool) {
  auto a = StartTestServer();
  auto b = StartTestServer();
  const std::string address_a = absl::StrCat("127.0.0.1:", a->port());
  const std::string address_b = absl::StrCat("127.0.0.1:", b->port());
  const std::string dir = TestDir("membership");
  const std::string file = dir + "/servers.txt";
  ASSERT_TRUE(WriteFileAtomically(file, address_a + "\n").ok());
  TrainerConfig config = TinyConfig({"file://" + file}, dir + "/run");
  config.iterations = 5;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  std::vector<int> live;
  std::vector<std::set<std::string>> servers;
  absl::Status status = (*trainer)->Run([&](const IterationStats& stats) {
    live.push_back(stats.live_sessions);
    servers.push_back(LiveServers(**trainer));
    if (stats.iteration == 1) ASSERT_TRUE(WriteFileAtomically(file, "# B joins\n" + address_a + "\n" + address_b + "\n").ok());
    if (stats.iteration == 3) ASSERT_TRUE(WriteFileAtomically(file, address_b + "\n").ok());
  });
  ASSERT_TRUE(status.ok()) << status;
  ASSERT_EQ(live.size(), 5u);
  EXPECT_EQ(live[0], 2);
  EXPECT_EQ(servers[0], std::set<std::string>{address_a});
  EXPECT_EQ(live[1], 4) << "B's two sessions join from the next iteration";
  EXPECT_EQ(servers[1], (std::set<std::string>{address_a, address_b}));
  EXPECT_EQ(live[3], 2) << "A is dropped from the next iteration";
  EXPECT_EQ(servers[4], std::set<std::string>{address_b});
  // A's slots were reused for nothing new: two servers' worth of slots over the whole run.
  EXPECT_EQ((*trainer)->servers().slots().size(), 4u);
  a->Shutdown(absl::Seconds(1));
  b->Shutdown(absl::Seconds(1));
}

}  // namespace
}  // namespace modskill::learner
