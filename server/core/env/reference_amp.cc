#include "server/core/env/reference_amp.h"

#include <algorithm>
#include <cstring>

#include "server/core/env/humanoid_state.h"
#include "server/core/env/observation.h"

namespace modskill {

ReferenceAmpFrames::ReferenceAmpFrames(const EnvSpec& spec, const MotionLibrary& motions)
    : per_frame_(spec.amp_obs_per_frame) {
  HumanoidState state;
  int64_t total = 0;
  for (int c = 0; c < motions.size(); ++c) {
    const MotionClip& clip = motions.clip(c);
    state.Resize(clip.num_bodies, clip.num_hinges());
    std::vector<float> table(static_cast<size_t>(clip.num_frames) * per_frame_);
    for (int f = 0; f < clip.num_frames; ++f) {
      ReadReferenceState(clip, f, &state);
      WriteAmpFrame(spec, state, &table[static_cast<size_t>(f) * per_frame_]);
    }
    frames_.push_back(std::move(table));
    total += clip.num_frames;
    cumulative_frames_.push_back(total);
  }
}

void ReferenceAmpFrames::WriteHistory(int clip, int frame, float* out) const {
  const std::vector<float>& table = frames_[clip];
  for (int k = 0; k < kAmpHistory; ++k) {
    const int f = std::max(0, frame - k);
    std::memcpy(out + static_cast<size_t>(k) * per_frame_, &table[static_cast<size_t>(f) * per_frame_],
                sizeof(float) * per_frame_);
  }
}

void ReferenceAmpFrames::Sample(int count, std::mt19937_64& rng, float* out) const {
  std::uniform_int_distribution<int64_t> pick(0, cumulative_frames_.back() - 1);
  for (int s = 0; s < count; ++s) {
    const int64_t global = pick(rng);
    const int clip = static_cast<int>(std::upper_bound(cumulative_frames_.begin(), cumulative_frames_.end(), global) -
                                      cumulative_frames_.begin());
    const int64_t first = clip == 0 ? 0 : cumulative_frames_[clip - 1];
    WriteHistory(clip, static_cast<int>(global - first), out + static_cast<size_t>(s) * kAmpHistory * per_frame_);
  }
}

}  // namespace modskill
