#include "server/core/motion/stance_feet.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace modskill {
namespace {

constexpr double kRadiansToDegrees = 57.29577951308232;

// The ankles, each with its toe (the body whose parent it is), -1 when the spec has none.
struct Foot {
  int ankle;
  int toe;
};

std::vector<Foot> Feet(const HumanoidSpec& spec) {
  std::vector<Foot> feet;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    if (spec.body(b).name.find("Ankle") == std::string::npos) continue;
    Foot foot{b, -1};
    for (int c = 0; c < spec.num_bodies(); ++c) {
      if (spec.body(c).parent == b) foot.toe = c;
    }
    feet.push_back(foot);
  }
  return feet;
}

double FootLowestPoint(const HumanoidSpec& spec, const MotionClip& clip, const Foot& foot, int frame) {
  const int ankle = frame * clip.num_bodies + foot.ankle;
  double lowest = spec.body(foot.ankle).geom.LowestPoint(clip.body_pos[ankle], clip.body_rot[ankle]);
  if (foot.toe >= 0) {
    const int toe = frame * clip.num_bodies + foot.toe;
    lowest = std::min(lowest, spec.body(foot.toe).geom.LowestPoint(clip.body_pos[toe], clip.body_rot[toe]));
  }
  return lowest;
}

bool InStance(const MotionClip& clip, const Foot& foot, int frame, double foot_lowest, double floor,
              const StanceFeetOptions& options) {
  return foot_lowest - floor < options.contact_height &&
         clip.body_vel[frame * clip.num_bodies + foot.ankle].norm() < options.max_speed;
}

}  // namespace

StanceFeet MeasureStanceFeet(const HumanoidSpec& spec, const MotionClip& clip, const StanceFeetOptions& options) {
  StanceFeet result;
  if (clip.body_pos.empty() || clip.body_vel.empty()) return result;
  const std::vector<Foot> feet = Feet(spec);
  double pitch_sum = 0, clearance_sum = 0;
  for (int f = 0; f < clip.num_frames; ++f) {
    for (const Foot& foot : feet) {
      const double lowest = FootLowestPoint(spec, clip, foot, f);
      if (!InStance(clip, foot, f, lowest, 0.0, options)) continue;
      const Vec3 forward = clip.body_rot[f * clip.num_bodies + foot.ankle] * Vec3::UnitX();
      pitch_sum += std::asin(std::clamp(forward.z(), -1.0, 1.0)) * kRadiansToDegrees;
      clearance_sum += lowest;
      ++result.stance_samples;
    }
  }
  if (result.stance_samples > 0) {
    result.mean_pitch_deg = pitch_sum / result.stance_samples;
    result.mean_clearance = clearance_sum / result.stance_samples;
  }
  return result;
}

std::vector<bool> StanceFrames(const HumanoidSpec& spec, const MotionClip& clip, const std::vector<double>& floor,
                               const std::vector<double>& lowest, const StanceFeetOptions& options) {
  std::vector<bool> stance(clip.num_frames, false);
  if (clip.body_pos.empty() || clip.body_vel.empty()) return stance;
  constexpr double kLowestBodyTolerance = 0.005;
  const std::vector<Foot> feet = Feet(spec);
  for (int f = 0; f < clip.num_frames; ++f) {
    for (const Foot& foot : feet) {
      const double foot_lowest = FootLowestPoint(spec, clip, foot, f);
      if (foot_lowest <= lowest[f] + kLowestBodyTolerance && InStance(clip, foot, f, foot_lowest, floor[f], options)) {
        stance[f] = true;
      }
    }
  }
  return stance;
}

}  // namespace modskill
