// modskill-policy-upgrade: re-exports a tracker's policy.pt written before skill composition with
// today's script (learner/policy_upgrade.h), so that it also defines skills(obs) and
// act_with_z(obs, z), which the server's composed rollouts need; a task policy's archive is saved
// again as it is. Same weights and spec; the new forward is checked against the old one on random
// observations before anything is written. A file from before policies recorded their physics
// gets the server's: run the server with the flags the policy was trained under (--substeps,
// --pd_mode, --pd_gain_scale, --damp_to_reference_rate). A motor-skill family's file is saved again
// as it is with the physics of a family session the server opens for its clip and ranges (stable
// PD, whatever the server's flags; the server's --substeps sets its rate).
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
#include "common/policy/policy_checkpoint.h"
#include "learner/family/family_session.h"
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

void PrintPhysicsAdded(const PolicyUpgrade& upgrade, const std::string& out, const std::string& where) {
  if (upgrade.physics_added) {
    std::printf("%s: now records the physics of %s: %s\n", out.c_str(), where.c_str(), upgrade.physics.ToJson().c_str());
  }
}

int UpgradeFamily(SimulationClient& client, const PolicySpec& spec, const std::string& in, const std::string& out) {
  auto session = family::DescribeFamilySession(client, spec);
  if (!session.ok()) return Fail(session.status());
  auto upgrade = UpgradeFamilyPolicy(in, *session, out);
  if (!upgrade.ok()) return Fail(upgrade.status());
  std::printf("%s: %s, a motor-skill family of '%s', saved again (forward differs by %.3g)\n", out.c_str(), in.c_str(),
              spec.family_clip.c_str(), upgrade->forward_difference);
  PrintPhysicsAdded(*upgrade, out, "its family session on " + absl::GetFlag(FLAGS_server));
  return 0;
}

int Upgrade(const std::string& in, const std::string& out) {
  auto checkpoint = PolicyCheckpoint::LoadFile(in);
  if (!checkpoint.ok()) return Fail(checkpoint.status());
  const PolicySpec spec = (*checkpoint)->spec();
  checkpoint->reset();
  ClientOptions options;
  options.server = absl::GetFlag(FLAGS_server);
  auto client = SimulationClient::Connect(options);
  if (!client.ok()) return Fail(client.status());
  if (spec.is_family()) return UpgradeFamily(**client, spec, in, out);
  auto exported = ReadExportedPolicy(in);
  if (!exported.ok()) return Fail(exported.status());
  auto described = (*client)->Describe(exported->spec.part_layout);
  if (!described.ok()) return Fail(described.status());
  auto upgrade = UpgradePolicy(*std::move(exported), *described, out);
  if (!upgrade.ok()) return Fail(upgrade.status());
  if (upgrade->rebuilt) {
    std::printf("%s: %s re-exported with skills() and act_with_z() (%d parts, z of %lld; forward differs by %.3g)\n",
                out.c_str(), in.c_str(), upgrade->parts, static_cast<long long>(upgrade->embed_dim),
                upgrade->forward_difference);
  } else {
    std::printf("%s: %s, a task policy, saved again (forward differs by %.3g)\n", out.c_str(), in.c_str(),
                upgrade->forward_difference);
  }
  PrintPhysicsAdded(*upgrade, out, options.server);
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
