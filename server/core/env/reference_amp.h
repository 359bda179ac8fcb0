// AMP features of every reference frame, computed once per batch: they seed each episode's AMP
// history and are the "expert" samples the discriminator learns from.
#ifndef MODSKILL_SERVER_CORE_ENV_REFERENCE_AMP_H_
#define MODSKILL_SERVER_CORE_ENV_REFERENCE_AMP_H_

#include <random>
#include <vector>

#include "server/core/env/env_spec.h"
#include "server/core/motion/motion_library.h"

namespace modskill {

class ReferenceAmpFrames {
 public:
  ReferenceAmpFrames(const EnvSpec& spec, const MotionLibrary& motions);

  int per_frame() const { return per_frame_; }
  // The kAmpHistory frames ending at `frame` (newest first; frames before 0 repeat frame 0).
  void WriteHistory(int clip, int frame, float* out) const;
  // `count` histories at clips and frames drawn uniformly over all frames of the library.
  void Sample(int count, std::mt19937_64& rng, float* out) const;

 private:
  int per_frame_;
  std::vector<std::vector<float>> frames_;  // per clip: [num_frames, per_frame]
  std::vector<int64_t> cumulative_frames_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_REFERENCE_AMP_H_
