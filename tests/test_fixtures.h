// Shared set-up for the simulation tests: the shipped skeleton and motion library, loaded once.
#ifndef MODSKILL_TESTS_TEST_FIXTURES_H_
#define MODSKILL_TESTS_TEST_FIXTURES_H_

#include <memory>

#include <gtest/gtest.h>

#include "server/core/env_batch.h"
#include "server/core/humanoid_spec.h"
#include "server/core/motion_library.h"

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

inline std::unique_ptr<EnvBatch> MakeBatch(EnvBatchConfig config,
                                           std::shared_ptr<const MotionLibrary> motions = DefaultMotions()) {
  auto batch = EnvBatch::Create(config, std::move(motions));
  EXPECT_TRUE(batch.ok()) << batch.status();
  return batch.ok() ? *std::move(batch) : nullptr;
}

// Actions whose PD targets are the reference pose of each env's next frame.
inline std::vector<float> ReferenceActions(const EnvBatch& batch) {
  const EnvSpec& spec = batch.spec();
  const HumanoidModel& humanoid = batch.humanoid();
  std::vector<float> actions(static_cast<size_t>(batch.num_envs()) * spec.action_size);
  for (int i = 0; i < batch.num_envs(); ++i) {
    const MotionClip& clip = batch.motions().clip(batch.buffers().clip_id[i]);
    const int frame = std::min(batch.buffers().frame[i] + 1, clip.num_frames - 1);
    for (int a = 0; a < spec.action_size; ++a) {
      const int h = spec.action_hinge[a];
      const double target = clip.dof_pos[frame * clip.num_hinges() + h];
      actions[i * spec.action_size + a] = static_cast<float>(
          std::clamp((target - humanoid.action_offset()[h]) / humanoid.action_scale()[h], -1.0, 1.0));
    }
  }
  return actions;
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_TEST_FIXTURES_H_
