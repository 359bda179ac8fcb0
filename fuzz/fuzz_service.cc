#include "fuzz/fuzz_service.h"

#include <cstdio>
#include <cstdlib>

#include "server/core/sim/humanoid_spec.h"

namespace modskill::fuzz {
namespace {

template <typename T>
T OrDie(absl::StatusOr<T> value, const char* what) {
  if (!value.ok()) {
    std::fprintf(stderr, "cannot load %s: %s\n", what, std::string(value.status().message()).c_str());
    std::abort();
  }
  return *std::move(value);
}

ServiceFixture* Load() {
  const HumanoidSpec skeleton = OrDie(HumanoidSpec::LoadDefault(), "the skeleton");
  auto* fixture = new ServiceFixture{OrDie(HumanoidModel::Create(skeleton, PhysicsOptions{}), "the humanoid"),
                                     OrDie(PartLayoutCatalog::LoadDefault(skeleton), "the part layouts"),
                                     {}};
  for (const std::string& name : fixture->layouts.Names()) {
    fixture->env_specs.emplace(name, MakeEnvSpec(*fixture->humanoid, OrDie(fixture->layouts.Get(name), "a layout")));
  }
  return fixture;
}

}  // namespace

const ServiceFixture& Fixture() {
  static const ServiceFixture* fixture = Load();
  return *fixture;
}

void Check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "invariant broken: %s\n", what);
  std::abort();
}

}  // namespace modskill::fuzz
