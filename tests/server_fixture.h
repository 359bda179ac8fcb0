// An in-process modskill server on an ephemeral port and a client connected to it.
#ifndef MODSKILL_TESTS_SERVER_FIXTURE_H_
#define MODSKILL_TESTS_SERVER_FIXTURE_H_

#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "client/cpp/simulation_client.h"
#include "server/service/server_runner.h"
#include "tests/test_fixtures.h"

namespace modskill {

inline std::unique_ptr<RunningServer> StartTestServer(ServerOptions options = ServerOptions()) {
  options.port = 0;
  options.bind = "127.0.0.1";
  auto server = StartServer(options, DefaultMotions());
  EXPECT_TRUE(server.ok()) << server.status();
  return server.ok() ? *std::move(server) : nullptr;
}

inline std::unique_ptr<SimulationClient> ConnectTo(const RunningServer& server, const std::string& token = "") {
  ClientOptions options;
  options.server = absl::StrCat("127.0.0.1:", server.port());
  options.token = token;
  options.connect_timeout = absl::Seconds(5);
  auto client = SimulationClient::Connect(options);
  EXPECT_TRUE(client.ok()) << client.status();
  return client.ok() ? *std::move(client) : nullptr;
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_SERVER_FIXTURE_H_
