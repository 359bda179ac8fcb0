// The server with TLS (issue 10): certificates are made at test time with the openssl command
// line (a throwaway CA, a server certificate for 127.0.0.1 and localhost signed by it, and a
// second CA that signed nothing). A client trusting the CA works; a plain-text client, a client
// trusting the other CA and a client checking another name fail fast with UNAVAILABLE; a server
// given half a key pair does not start.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gmock/gmock.h>

#include "absl/strings/str_cat.h"
#include "tests/server_fixture.h"
#include "tests/test_files.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

// Failing handshakes end in Connect's timeout; short, so the suite stays at a few seconds.
constexpr absl::Duration kFailingConnectTimeout = absl::Seconds(1);

bool HaveOpenssl() { return std::system("openssl version > /dev/null 2>&1") == 0; }

// Runs `command` in `directory`, its output appended to openssl.log there.
void RunIn(const std::filesystem::path& directory, const std::string& command) {
  const std::string line = absl::StrCat("cd '", directory.string(), "' && ", command, " >> openssl.log 2>&1");
  ASSERT_EQ(std::system(line.c_str()), 0) << line << "\n(see " << (directory / "openssl.log").string() << ")";
}

// P-256 keys: generated in milliseconds, unlike RSA.
constexpr char kNewKey[] = "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";

void MakeCa(const std::filesystem::path& directory, const std::string& name) {
  RunIn(directory, absl::StrCat("openssl req -x509 ", kNewKey, " -days 1 -subj '/CN=modskill test ", name,
                                "' -keyout ", name, ".key -out ", name, ".crt"));
}

class TlsServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!HaveOpenssl()) return;
    // ctest runs each test in its own process, possibly in parallel: one directory per process.
    directory_ = new std::filesystem::path(std::filesystem::path(MODSKILL_TEST_TMP_DIR) / "tls_server" /
                                           absl::StrCat(getpid()));
    std::filesystem::remove_all(*directory_);
    std::filesystem::create_directories(*directory_);
    MakeCa(*directory_, "ca");
    MakeCa(*directory_, "other_ca");
    RunIn(*directory_, absl::StrCat("openssl req ", kNewKey, " -subj /CN=localhost -keyout server.key -out server.csr"));
    WriteBytes((*directory_ / "server.ext").string(),
               "subjectAltName=IP:127.0.0.1,DNS:localhost\nbasicConstraints=CA:FALSE\nextendedKeyUsage=serverAuth\n");
    RunIn(*directory_,
          "openssl x509 -req -in server.csr -CA ca.crt -CAkey ca.key -CAcreateserial -days 1 "
          "-extfile server.ext -out server.crt");
  }

  static void TearDownTestSuite() {
    if (directory_ != nullptr) std::filesystem::remove_all(*directory_);
  }

  void SetUp() override {
    if (!HaveOpenssl()) GTEST_SKIP() << "the openssl command is not installed (Debian: apt-get install openssl)";
    ASSERT_TRUE(std::filesystem::exists(File("server.crt"))) << "certificate set-up failed";
  }

  static std::string File(const std::string& name) { return (*directory_ / name).string(); }

  std::unique_ptr<RunningServer> StartTlsServer() {
    ServerOptions options;
    options.tls_cert_file = File("server.crt");
    options.tls_key_file = File("server.key");
    return StartTestServer(options);
  }

  static absl::StatusOr<std::unique_ptr<SimulationClient>> ConnectWith(const RunningServer& server,
                                                                       const std::string& ca_file,
                                                                       absl::Duration timeout,
                                                                       const std::string& server_name = "") {
    ClientOptions options;
    options.server = absl::StrCat("127.0.0.1:", server.port());
    options.tls_ca_file = ca_file.empty() ? "" : File(ca_file);
    options.tls_server_name = server_name;
    options.connect_timeout = timeout;
    return SimulationClient::Connect(options);
  }

  static std::filesystem::path* directory_;
};

std::filesystem::path* TlsServerTest::directory_ = nullptr;

TEST_F(TlsServerTest, ClientTrustingTheCaDescribes) {
  auto server = StartTlsServer();
  ASSERT_NE(server, nullptr);
  auto client = ConnectWith(*server, "ca.crt", absl::Seconds(5));
  ASSERT_TRUE(client.ok()) << client.status();
  auto spec = (*client)->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_GT(spec->obs_size(), 0);
  // The certificate also names localhost: a client checking that name is served too.
  auto by_name = ConnectWith(*server, "ca.crt", absl::Seconds(5), "localhost");
  ASSERT_TRUE(by_name.ok()) << by_name.status();
  EXPECT_TRUE((*by_name)->Describe().ok());
  server->Shutdown(absl::Seconds(1));
}

TEST_F(TlsServerTest, PlainTextClientFailsFast) {
  auto server = StartTlsServer();
  ASSERT_NE(server, nullptr);
  const absl::Time start = absl::Now();
  auto client = ConnectWith(*server, "", kFailingConnectTimeout);
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), absl::StatusCode::kUnavailable) << client.status();
  EXPECT_THAT(client.status().message(), HasSubstr("no answer within"));
  EXPECT_LT(absl::Now() - start, kFailingConnectTimeout + absl::Seconds(2));

  // A call on a plain-text channel (no Connect wait) ends at once or at its deadline, never hangs.
  auto channel = grpc::CreateChannel(absl::StrCat("127.0.0.1:", server->port()), grpc::InsecureChannelCredentials());
  auto stub = v1::Simulation::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(absl::ToChronoTime(absl::Now() + kFailingConnectTimeout));
  v1::EnvSpec spec;
  const grpc::Status status = stub->Describe(&context, v1::DescribeRequest(), &spec);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(status.error_code(), ::testing::AnyOf(grpc::StatusCode::UNAVAILABLE, grpc::StatusCode::DEADLINE_EXCEEDED))
      << status.error_message();
  server->Shutdown(absl::Seconds(1));
}

TEST_F(TlsServerTest, ClientTrustingAnotherCaFails) {
  auto server = StartTlsServer();
  ASSERT_NE(server, nullptr);
  auto client = ConnectWith(*server, "other_ca.crt", kFailingConnectTimeout);
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), absl::StatusCode::kUnavailable) << client.status();
  server->Shutdown(absl::Seconds(1));
}

TEST_F(TlsServerTest, ClientCheckingAnotherNameFails) {
  auto server = StartTlsServer();
  ASSERT_NE(server, nullptr);
  auto client = ConnectWith(*server, "ca.crt", kFailingConnectTimeout, "sim-node-1.example");
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), absl::StatusCode::kUnavailable) << client.status();
  server->Shutdown(absl::Seconds(1));
}

TEST_F(TlsServerTest, ClientWithMissingCaFileSaysSo) {
  ClientOptions options;
  options.server = "127.0.0.1:1";
  options.tls_ca_file = File("no_such_ca.crt");
  auto client = SimulationClient::Connect(options);
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(client.status().message(), HasSubstr("tls_ca"));
}

absl::Status StartWith(const std::string& cert, const std::string& key) {
  ServerOptions options;
  options.port = 0;
  options.tls_cert_file = cert;
  options.tls_key_file = key;
  auto server = StartServer(options, DefaultMotions());
  if (server.ok()) (*server)->Shutdown(absl::Seconds(0));
  return server.status();
}

TEST_F(TlsServerTest, ServerWithoutItsKeyDoesNotStart) {
  const absl::Status no_key = StartWith(File("server.crt"), "");
  EXPECT_EQ(no_key.code(), absl::StatusCode::kInvalidArgument) << no_key;
  EXPECT_THAT(no_key.message(), HasSubstr("tls_key"));

  const absl::Status no_cert = StartWith("", File("server.key"));
  EXPECT_EQ(no_cert.code(), absl::StatusCode::kInvalidArgument) << no_cert;
  EXPECT_THAT(no_cert.message(), HasSubstr("tls_cert"));

  const absl::Status missing_key = StartWith(File("server.crt"), File("no_such.key"));
  EXPECT_EQ(missing_key.code(), absl::StatusCode::kInvalidArgument) << missing_key;
  EXPECT_THAT(missing_key.message(), HasSubstr("tls_key"));
  EXPECT_THAT(missing_key.message(), HasSubstr("no_such.key"));
}

TEST_F(TlsServerTest, ServerWithKeyOfAnotherCertificateDoesNotStart) {
  // ca.key is a valid key, but not server.crt's.
  const absl::Status mismatched = StartWith(File("server.crt"), File("ca.key"));
  EXPECT_EQ(mismatched.code(), absl::StatusCode::kInvalidArgument) << mismatched;
  EXPECT_THAT(mismatched.message(), HasSubstr("matching private key"));

  WriteBytes(File("garbage.key"), "not a PEM key\n");
  const absl::Status garbage = StartWith(File("server.crt"), File("garbage.key"));
  EXPECT_EQ(garbage.code(), absl::StatusCode::kInvalidArgument) << garbage;
  EXPECT_THAT(garbage.message(), HasSubstr("garbage.key"));
}

}  // namespace
}  // namespace modskill
