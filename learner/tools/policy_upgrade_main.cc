// modskill-policy-upgrade: re-exports a tracker's policy.pt written before skill composition with
// today's script (learner/policy_upgrade.h), so that it also defines skills(obs) and
// act_with_z(obs, z), which the server's composed rollouts need; a task policy's archive is saved
// again as it is. Same weights and spec; the new forward is checked against the old one on random
// observations before anything is written. A file from before policies recorded their physics
// gets the server's: run the server with the flags the policy was trained under (--substeps,
// --pd_mode, --pd_gain_scale, --damp_to_reference_rate). A motor-skill family's file is refused.
//
//   modskill-policy-upgrade [--server host:port] IN.pt OUT.pt
//
// The server (Describe) gives the part layout's observation slices, which the file does not hold.
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "client/cpp/simulation_client.h"
#include "learner/policy_import.h"
#include "learner/policy_upgrade.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051",
          "a modskill server (host:port) that describes the policy's layout, running the physics it was trained in");

namespace modskill::learner {
namespace {

int Fail(const absl::Status& status) {
  std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
  return 1;
}

int Upgrade(const std::string& in, const std::string& out) {
  auto exported = ReadExportedPolicy(in);
  if (!exported.ok()) return Fail(exported.status());
  ClientOptions options;
  options.server = absl::GetFlag(FLAGS_server);
  auto client = SimulationClient::Connect(options);
  if (!client.ok()) return Fail(client.status());
  auto spec = (*client)->Describe(exported->spec.part_layout);
  if (!spec.ok()) return Fail(spec.status());
  auto upgrade = UpgradePolicy(*std::move(exported), *spec, out);
  if (!upgrade.ok()) return Fail(upgrade.status());
  if (upgrade->rebuilt) {
    std::printf("%s: %s re-exported with skills() and act_with_z() (%d parts, z of %lld; forward differs by %.3g)\n",
                out.c_str(), in.c_str(), upgrade->parts, static_cast<long long>(upgrade->embed_dim),
                upgrade->forward_difference);
  } else {
    std::printf("%s: %s, a task policy, saved again (forward differs by %.3g)\n", out.c_str(), in.c_str(),
                upgrade->forward_difference);
  }
  if (upgrade->physics_added) {
    std::printf("%s: now records the physics of %s: %s\n", out.c_str(), options.server.c_str(),
                upgrade->physics.ToJson().c_str());
  }
  return 0;
}

}  // namespace
}  // namespace modskill::learner

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("modskill-policy-upgrade [--server host:port] IN.pt OUT.pt");
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  if (args.size() != 3) {
    std::fprintf(stderr, "usage: modskill-policy-upgrade [--server host:port] IN.pt OUT.pt\n");
    return 2;
  }
  return modskill::learner::Upgrade(args[1], args[2]);
}
