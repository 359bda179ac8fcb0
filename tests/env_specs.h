// The server's env spec of the shipped humanoid for a part layout and task, in memory and as the
// wire describes it to the learner; built once per (layout, task). For learner tests that need
// a spec without a server.
#ifndef MODSKILL_TESTS_ENV_SPECS_H_
#define MODSKILL_TESTS_ENV_SPECS_H_

#include <map>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "server/core/env/env_spec.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/core/sim/physics_options.h"
#include "server/service/proto_conversions.h"

namespace modskill {

struct Specs {
  EnvSpec env;
  v1::EnvSpec wire;
};

inline const Specs& SpecsOf(const std::string& layout_name, TaskKind task = TaskKind::kTracking) {
  static auto* specs = new std::map<std::pair<std::string, TaskKind>, Specs>();
  auto it = specs->find({layout_name, task});
  if (it != specs->end()) return it->second;
  auto humanoid_spec = HumanoidSpec::LoadDefault();
  EXPECT_TRUE(humanoid_spec.ok()) << humanoid_spec.status();
  auto humanoid = HumanoidModel::Create(*humanoid_spec, PhysicsOptions());
  EXPECT_TRUE(humanoid.ok()) << humanoid.status();
  auto catalog = PartLayoutCatalog::LoadDefault(*humanoid_spec);
  EXPECT_TRUE(catalog.ok()) << catalog.status();
  auto layout = catalog->Get(layout_name);
  EXPECT_TRUE(layout.ok()) << layout.status();
  Specs made{MakeEnvSpec(**humanoid, *layout, task), {}};
  ToProto(made.env, **humanoid, &made.wire);
  return specs->emplace(std::make_pair(layout_name, task), std::move(made)).first->second;
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_ENV_SPECS_H_
