// modskill-policy-upgrade: re-exports a tracker's policy.pt written before skill composition with
// today's script (learner/policy_export.h), so that it also defines skills(obs) and
// act_with_z(obs, z), which the server's composed rollouts need. Same weights and spec; the new
// forward is checked against the old one on random observations before anything is written.
//
//   modskill-policy-upgrade [--server host:port] IN.pt OUT.pt
//
// The server (Describe) gives the part layout's observation slices, which the file does not hold.
#include <cstdio>
#include <string>
#include <vector>

#include <torch/script.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "client/cpp/simulation_client.h"
#include "learner/model_config.h"
#include "learner/policy_export.h"
#include "learner/policy_import.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "a modskill server (host:port) that describes the policy's layout");

namespace modskill::learner {
namespace {

int Fail(const absl::Status& status) {
  std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
  return 1;
}

// The largest |old forward - new forward| over random raw observations (scaled like real ones).
absl::StatusOr<double> ForwardDifference(const std::string& old_path, const std::string& new_path, int64_t obs_size) {
  try {
    torch::NoGradGuard no_grad;
    torch::manual_seed(1);
    const torch::Tensor obs = torch::randn({64, obs_size}) * 2.0;
    torch::jit::Module before = torch::jit::load(old_path), after = torch::jit::load(new_path);
    const torch::Tensor a = before.forward({obs}).toTensor(), b = after.forward({obs}).toTensor();
    const torch::Tensor composed =
        after.get_method("act_with_z")({obs, after.get_method("skills")({obs}).toTensor()}).toTensor();
    return std::max((a - b).abs().max().item<double>(), (a - composed).abs().max().item<double>());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("checking the export: ", message.substr(0, message.find('\n'))));
  }
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
  const NetworkLayout layout = LayoutFromWireSpec(*spec);
  if (absl::Status valid = layout.Validate(); !valid.ok()) return Fail(valid);
  auto rebuilt = RebuildTracker(*exported, layout);
  if (!rebuilt.ok()) return Fail(rebuilt.status());
  // What the rebuilt controllers read, also for files from before the spec recorded it.
  exported->spec.controller_input = ControllerInputName(rebuilt->policy->config().controller_input);
  // Written beside OUT first, so that a failed check leaves OUT alone.
  const std::string staged = out + ".upgrade";
  if (absl::Status status = ExportPolicy(rebuilt->policy, rebuilt->obs_norm, exported->spec, staged); !status.ok()) {
    return Fail(status);
  }
  auto difference = ForwardDifference(in, staged, layout.obs_size);
  if (!difference.ok() || *difference > 1e-5) {
    std::remove(staged.c_str());
    return Fail(difference.ok() ? absl::InternalError(absl::StrCat("the re-exported forward differs from ", in, " by ",
                                                                   *difference))
                                : difference.status());
  }
  if (std::rename(staged.c_str(), out.c_str()) != 0) {
    std::remove(staged.c_str());
    return Fail(absl::InternalError(absl::StrCat(out, ": cannot move ", staged, " there")));
  }
  std::printf("%s: %s re-exported with skills() and act_with_z() (%zu parts, z of %lld; forward differs by %.3g)\n",
              out.c_str(), in.c_str(), layout.parts.size(),
              static_cast<long long>(rebuilt->policy->config().embed_dim), *difference);
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
