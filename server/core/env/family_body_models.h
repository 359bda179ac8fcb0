// The humanoid at other body proportions for a motor-skill family's leg_scale and arm_scale
// (Lee et al. 2021 vary limb lengths and radii): HumanoidSpec::Scaled compiled into its own
// mjModel, once per value pair at kBodyScaleResolution and cached, shared by a session's envs. An
// env copies the scaled model's numbers into its own model copy at an episode's start (same
// structure, so no allocation) and reads its kinematics with the scaled spec.
#ifndef MODSKILL_SERVER_CORE_ENV_FAMILY_BODY_MODELS_H_
#define MODSKILL_SERVER_CORE_ENV_FAMILY_BODY_MODELS_H_

#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_model.h"

namespace modskill {

inline constexpr double kBodyScaleResolution = 0.01;  // the scales a model is compiled at
inline constexpr size_t kMaxCachedBodyModels = 2048;  // 67 KB each: 137 MB at most, per session

// The bodies a scale applies to, lengths and radii alike (FamilyLimbScale).
BodyScaling FamilyBodyScaling(const HumanoidSpec& spec, double leg_scale, double arm_scale);

// The clip on a scaled skeleton: the same joint rotations, the root's travel from its first frame
// scaled by leg_scale (a longer stride), then placed on the ground. `out` keeps its buffers.
absl::Status ScaleClip(const MotionClip& clip, const HumanoidSpec& scaled, double leg_scale, MotionClip* out);

class FamilyBodyModels {
 public:
  explicit FamilyBodyModels(std::shared_ptr<const HumanoidModel> base) : base_(std::move(base)) {}

  // The humanoid at (leg_scale, arm_scale) rounded to kBodyScaleResolution. Thread-safe; a value
  // pair compiles once (milliseconds) while it stays among the kMaxCachedBodyModels latest.
  // INTERNAL when its model's layout differs from the base model's (it could not be copied in).
  absl::StatusOr<std::shared_ptr<const HumanoidModel>> Get(double leg_scale, double arm_scale);

 private:
  std::shared_ptr<const HumanoidModel> base_;
  std::mutex mutex_;
  std::map<std::pair<int, int>, std::shared_ptr<const HumanoidModel>> cache_;
  std::deque<std::pair<int, int>> order_;  // oldest first
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_FAMILY_BODY_MODELS_H_
