// make_test_policy: writes the zero affine policy (every joint held at its range midpoint) as a
// TorchScript checkpoint for the default humanoid, so that tests of Rollout have a checkpoint
// without a training run.
//
//   make_test_policy OUT.pt [--layout NAME]
//
// NAME is a part layout of data/part_layouts.json (default: the catalog's default, 5part).
#include <cstdio>
#include <cstring>
#include <string>

#include "common/policy/policy_checkpoint.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/policy_fit.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/core/sim/physics_options.h"

namespace {

int Usage(const char* argv0) {
  std::fprintf(stderr, "usage: %s OUT.pt [--layout NAME]\n", argv0);
  return 2;
}

int Fail(const std::string& what, const std::string& message) {
  std::fprintf(stderr, "make_test_policy: %s: %s\n", what.c_str(), message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace modskill;
  std::string out, layout_name;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--layout" && i + 1 < argc) {
      layout_name = argv[++i];
    } else if (arg.rfind("--layout=", 0) == 0) {
      layout_name = arg.substr(std::strlen("--layout="));
    } else if (arg == "-h" || arg == "--help") {
      Usage(argv[0]);
      return 0;
    } else if (!arg.empty() && arg[0] != '-' && out.empty()) {
      out = arg;
    } else {
      return Usage(argv[0]);
    }
  }
  if (out.empty()) return Usage(argv[0]);

  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return Fail("skeleton", std::string(spec.status().message()));
  auto humanoid = HumanoidModel::Create(*spec, PhysicsOptions());
  if (!humanoid.ok()) return Fail("humanoid", std::string(humanoid.status().message()));
  auto catalog = PartLayoutCatalog::LoadDefault(*spec);
  if (!catalog.ok()) return Fail("part layouts", std::string(catalog.status().message()));
  auto layout = catalog->Get(layout_name.empty() ? catalog->default_name() : layout_name);
  if (!layout.ok()) return Fail("--layout", std::string(layout.status().message()));

  const EnvSpec env_spec = MakeEnvSpec(**humanoid, *layout);
  const PolicySpec policy_spec = PolicySpecForEnv(env_spec);
  // Empty weight: zeros; zero bias: every action 0, i.e. the PD target at the range midpoint.
  const std::vector<float> bias(policy_spec.action_size, 0.0f);
  if (auto status = SaveAffinePolicy(out, policy_spec, {}, bias); !status.ok()) {
    return Fail(out, std::string(status.message()));
  }
  std::printf("%s: zero affine policy, layout %s, obs %d, actions %d\n", out.c_str(), layout->name.c_str(),
              policy_spec.obs_size, policy_spec.action_size);
  return 0;
}
