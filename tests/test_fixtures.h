// Shared set-up for the simulation tests: the shipped skeleton and motion library, loaded once.
#ifndef MODSKILL_TESTS_TEST_FIXTURES_H_
#define MODSKILL_TESTS_TEST_FIXTURES_H_

#include <cstdlib>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "server/core/env/env_batch.h"
#include "server/core/env/reference_actions.h"
#include "server/core/motion/motion_library.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

inline const HumanoidSpec& DefaultSpec() {
  static const HumanoidSpec* spec = [] {
    auto loaded = HumanoidSpec::LoadDefault();
    if (!loaded.ok()) {
      ADD_FAILURE() << loaded.status();
      std::abort();
    }
    return new HumanoidSpec(*loaded);
  }();
  return *spec;
}

inline std::shared_ptr<const MotionLibrary> DefaultMotions() {
  static std::shared_ptr<const MotionLibrary> motions = [] {
    auto loaded = MotionLibrary::LoadDefault(DefaultSpec());
    if (!loaded.ok()) {
      ADD_FAILURE() << loaded.status();
      std::abort();
    }
    return std::make_shared<const MotionLibrary>(*std::move(loaded));
  }();
  return motions;
}

// A clip of the shipped library by name; a missing one fails the test at once.
inline const MotionClip& ShippedClip(const std::string& name) {
  const int id = DefaultMotions()->Find(name);
  if (id < 0) {
    ADD_FAILURE() << "no shipped clip " << name;
    std::abort();
  }
  return DefaultMotions()->clip(id);
}

inline std::unique_ptr<EnvBatch> MakeBatch(EnvBatchConfig config,
                                           std::shared_ptr<const MotionLibrary> motions = DefaultMotions()) {
  auto batch = EnvBatch::Create(config, std::move(motions));
  EXPECT_TRUE(batch.ok()) << batch.status();
  return batch.ok() ? *std::move(batch) : nullptr;
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_TEST_FIXTURES_H_
