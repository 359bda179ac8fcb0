// Shared set-up of the fuzz targets for what the server checks before it simulates (policy
// specs, Simulate requests): the shipped humanoid and part layouts, loaded once, and the env
// spec of every layout, as the service holds them.
#ifndef MODSKILL_FUZZ_FUZZ_SERVICE_H_
#define MODSKILL_FUZZ_FUZZ_SERVICE_H_

#include <map>
#include <memory>
#include <string>

#include "server/core/env/env_spec.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/part_layout.h"

namespace modskill::fuzz {

struct ServiceFixture {
  std::shared_ptr<const HumanoidModel> humanoid;
  PartLayoutCatalog layouts;
  std::map<std::string, EnvSpec> env_specs;  // by layout name
};

// Loads the fixture on the first call (from LLVMFuzzerInitialize); aborts if the data is missing.
const ServiceFixture& Fixture();

// Aborts, naming `what`, unless `condition` holds: a broken invariant is a crash for libFuzzer.
void Check(bool condition, const char* what);

}  // namespace modskill::fuzz

#endif  // MODSKILL_FUZZ_FUZZ_SERVICE_H_
