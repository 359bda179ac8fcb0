#include "server/core/curriculum/motion_variants.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "server/core/curriculum/plausibility_filter.h"
#include "server/core/util/seed_mixing.h"

namespace modskill {
namespace {

// Largest |pitch| (the middle, y hinge) a rebuilt rotation may have: at exactly pi/2 the x-y-z
// decomposition is gimbal locked and would fold the z angle into x, possibly out of range.
constexpr double kMaxPitch = M_PI / 2 - 1e-3;
// The ground correction may be smoothed this far away from the exact one (m).
constexpr double kGroundSmoothingSlack = 0.01;
// Integration steps of the time warp per parent frame.
constexpr int kWarpStepsPerFrame = 16;
// A parent foot on the floor that moves slower than this (m/s) is planted: the root is anchored to it.
constexpr double kPlantedFootSpeed = 0.3;
// Contact-aware attenuation: a foot on the floor may slide this much faster than the parent's
// (m/s) before the displaced legs' displacements are scaled down around that frame, over a
// raised-cosine window of this half width (s), for at most this many rounds (each halves the gain
// at a sliding frame, so the legs tend to the parent's motion there).
constexpr double kSkateTolerance = 0.25;
constexpr double kAttenuationHalfWidth = 0.15;
constexpr int kMaxAttenuationRounds = 8;

// A small, portable, seedable generator (SplitMix64): identical streams on every platform and
// standard library, unlike std::uniform_real_distribution.
class VariantRng {
 public:
  VariantRng(uint64_t seed, uint64_t stream) : state_(Mix(seed) ^ Mix(stream * 0xD1B54A32D192ED03ull + 1)) {}
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double low, double high) { return low + (high - low) * Uniform(); }

 private:
  static uint64_t Mix(uint64_t z) { return MixSeed(z); }
  uint64_t Next() { return Mix(state_ += 0x9E3779B97F4A7C15ull); }
  uint64_t state_;
};

// Random knots spread evenly over the clip's phase [0, 1], joined by smoothstep segments: C1,
// and each value a convex blend of two knots, so bounded by the largest knot.
template <typename T>
T EvaluateKnots(const std::vector<T>& knots, double phase) {
  const int segments = static_cast<int>(knots.size()) - 1;
  const double x = std::clamp(phase, 0.0, 1.0) * segments;
  const int i = std::min(static_cast<int>(x), segments - 1);
  const double u = x - i;
  const double w = u * u * (3.0 - 2.0 * u);
  return (1.0 - w) * knots[i] + w * knots[i + 1];
}

// A rotation vector with a uniformly random direction and a length in [amplitude / 4, amplitude].
Vec3 RandomDisplacementKnot(VariantRng& rng, double amplitude) {
  const double z = rng.Uniform(-1.0, 1.0);
  const double azimuth = rng.Uniform(0.0, 2.0 * M_PI);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double length = amplitude * rng.Uniform(0.25, 1.0);
  return length * Vec3(r * std::cos(azimuth), r * std::sin(azimuth), z);
}

bool HasKinematics(const MotionClip& clip) {
  const size_t rows = static_cast<size_t>(clip.num_frames) * clip.num_bodies;
  return clip.body_pos.size() == rows && clip.body_rot.size() == rows && clip.body_vel.size() == rows &&
         clip.dof_pos.size() == static_cast<size_t>(clip.num_frames) * clip.num_hinges();
}

absl::Status ValidateOptions(const HumanoidSpec& spec, const PartLayout& layout, const MotionClip& parent,
                             const VariantOptions& options) {
  if (options.count < 1 || options.count > 64) {
    return absl::InvalidArgumentError(absl::StrCat("VariantOptions.count = ", options.count, " outside [1, 64]"));
  }
  if (options.part < -1 || options.part >= layout.num_parts()) {
    return absl::InvalidArgumentError(absl::StrCat("VariantOptions.part = ", options.part, " outside [-1, ",
                                                   layout.num_parts() - 1, "] (layout '", layout.name, "')"));
  }
  if (!(options.rotation_amplitude >= 0 && options.rotation_amplitude <= 1.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("VariantOptions.rotation_amplitude = ", options.rotation_amplitude, " outside [0, 1.5] rad"));
  }
  if (!(options.time_warp_amplitude >= 0 && options.time_warp_amplitude <= 0.9)) {
    return absl::InvalidArgumentError(
        absl::StrCat("VariantOptions.time_warp_amplitude = ", options.time_warp_amplitude, " outside [0, 0.9]"));
  }
  if (options.knots < 2 || options.knots > 64) {
    return absl::InvalidArgumentError(absl::StrCat("VariantOptions.knots = ", options.knots, " outside [2, 64]"));
  }
  for (const BodyPart& part : layout.parts) {
    for (int body : part.bodies) {
      if (body < 0 || body >= spec.num_bodies()) {
        return absl::InvalidArgumentError(absl::StrCat("layout '", layout.name, "': part '", part.name, "' has body ",
                                                       body, " but the skeleton has ", spec.num_bodies()));
      }
    }
  }
  const std::string where = absl::StrCat("parent clip '", parent.name, "'");
  if (parent.num_frames < 2) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": num_frames ", parent.num_frames, " < 2"));
  }
  if (parent.num_bodies != spec.num_bodies()) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": ", parent.num_bodies, " bodies but the skeleton has ", spec.num_bodies()));
  }
  if (auto status = ValidateClip(parent); !status.ok()) return status;
  if (!HasKinematics(parent)) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": no kinematics (run ComputeClipKinematics first)"));
  }
  return absl::OkStatus();
}

// Parent time (s) of each output frame for a warp with speed 1 + a * w(phase): integrates
// dt/dphi = 1 / speed over the parent's duration, picks the frame count and inverts.
std::vector<double> WarpedSourceTimes(const MotionClip& parent, double amplitude, const std::vector<double>& knots) {
  const double duration = parent.duration(), fps = parent.fps;
  const int steps = kWarpStepsPerFrame * (parent.num_frames - 1);
  auto inverse_speed = [&](int step) { return 1.0 / (1.0 + amplitude * EvaluateKnots(knots, double(step) / steps)); };
  std::vector<double> variant_time(steps + 1, 0.0);  // variant time at parent time duration * step / steps
  for (int s = 0; s < steps; ++s) {
    variant_time[s + 1] = variant_time[s] + duration / steps * 0.5 * (inverse_speed(s) + inverse_speed(s + 1));
  }
  const double warped_duration = variant_time[steps];
  // Frame count: the warped duration at the parent's fps, kept inside the bounds the amplitude
  // promises (rounding may not leave them).
  const int shortest = static_cast<int>(std::ceil(duration / (1.0 + amplitude) * fps - 1e-9)) + 1;
  const int longest = static_cast<int>(std::floor(duration / (1.0 - amplitude) * fps + 1e-9)) + 1;
  const int frames = std::clamp(static_cast<int>(std::lround(warped_duration * fps)) + 1, std::max(2, shortest),
                                std::max(2, longest));
  // Stretch the warp by (frames - 1) / fps / warped_duration (within half a frame) so that the
  // last frame lands exactly on the parent's last frame.
  std::vector<double> source_time(frames);
  int s = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = warped_duration * f / (frames - 1);
    while (s < steps - 1 && variant_time[s + 1] < t) ++s;
    const double span = variant_time[s + 1] - variant_time[s];
    const double u = span > 0 ? std::clamp((t - variant_time[s]) / span, 0.0, 1.0) : 0.0;
    source_time[f] = duration * (s + u) / steps;
  }
  source_time.front() = 0.0;
  source_time.back() = duration;
  return source_time;
}

// Decomposes q into hinge angles, clamps them to the body's ranges and rebuilds it.
Quat ClampToHingeRanges(const BodySpec& body, const Quat& q) {
  Vec3 angles = HingeAngles(q);
  for (int a = 0; a < 3; ++a) {
    double low = body.range_low[a], high = body.range_high[a];
    if (a == 1) {
      low = std::max(low, -kMaxPitch);
      high = std::min(high, kMaxPitch);
    }
    angles[a] = std::clamp(angles[a], std::min(low, high), high);
  }
  return HingeRotation(angles[0], angles[1], angles[2]);
}

// Where each variant frame samples the parent: parent time, and frame f0 + alpha between f0, f0 + 1.
struct Timing {
  std::vector<double> source_time;
  std::vector<int> f0;
  std::vector<double> alpha;
  std::vector<double> rate;  // d(parent time) / d(variant time), the warp's speed

  Timing(const MotionClip& parent, std::vector<double> times) : source_time(std::move(times)) {
    const int frames = static_cast<int>(source_time.size());
    f0.resize(frames);
    alpha.resize(frames);
    rate.resize(frames);
    for (int f = 0; f < frames; ++f) {
      const double x = std::clamp(source_time[f] * parent.fps, 0.0, parent.num_frames - 1.0);
      f0[f] = std::min(static_cast<int>(x), parent.num_frames - 2);
      alpha[f] = x - f0[f];
      const int a = std::max(0, f - 1), b = std::min(frames - 1, f + 1);
      rate[f] = (source_time[b] - source_time[a]) / ((b - a) / parent.fps);
    }
  }
  int num_frames() const { return static_cast<int>(source_time.size()); }
  template <typename T>
  T Lerp(const std::vector<T>& per_parent_frame, int f, int stride = 1, int offset = 0) const {
    return (1 - alpha[f]) * per_parent_frame[f0[f] * stride + offset] +
           alpha[f] * per_parent_frame[(f0[f] + 1) * stride + offset];
  }
};

// What the contact handling of a leg variant follows, per parent frame.
struct ParentContacts {
  std::vector<double> lowest;              // lowest geometry point [frame]
  std::vector<int> feet;                   // FootBodies
  std::vector<double> foot_height;         // lowest point of each foot's geometry [frame * feet + i]
  std::vector<Eigen::Vector2d> foot_xy;    // horizontal position of each foot body [frame * feet + i]
  std::vector<double> foot_speed;          // horizontal speed of each foot body [frame * feet + i]

  ParentContacts(const HumanoidSpec& spec, const MotionClip& parent) : feet(FootBodies(spec)) {
    const int frames = parent.num_frames, n = static_cast<int>(feet.size());
    lowest.resize(frames);
    foot_height.resize(static_cast<size_t>(frames) * n);
    foot_xy.resize(static_cast<size_t>(frames) * n);
    foot_speed.resize(static_cast<size_t>(frames) * n);
    for (int f = 0; f < frames; ++f) {
      lowest[f] = LowestGeomPoint(spec, parent, f);
      for (int i = 0; i < n; ++i) {
        foot_height[f * n + i] = BodyGeomBottom(spec, parent, f, feet[i]);
        foot_xy[f * n + i] = parent.body_pos[f * parent.num_bodies + feet[i]].head<2>();
        foot_speed[f * n + i] = parent.body_vel[f * parent.num_bodies + feet[i]].head<2>().norm();
      }
    }
  }
  int num_feet() const { return static_cast<int>(feet.size()); }
};

// Keeps a leg variant's contacts where the parent has them, by moving the root only:
//   horizontally, while a parent foot is planted (its geometry within kFootContactHeight of the
//   floor and its horizontal speed below kPlantedFootSpeed, fading out at twice those), the root
//   is shifted so that the variant's foot moves as the parent's does over the same (warped) time,
//   i.e. stays planted: per frame, the root's step is corrected by the weighted mean of the feet's
//   step errors (so one planted foot is pinned exactly; in double support the feet share it);
//   vertically, the root height is shifted so that the lowest geometry point follows the
//   parent's, by the exact correction smoothed with a 5-tap binomial filter and kept within
//   kGroundSmoothingSlack of the exact one.
// Needs and recomputes kinematics.
absl::Status AnchorToParentContacts(const HumanoidSpec& spec, const ParentContacts& contacts, const Timing& timing,
                                    MotionClip* clip) {
  const int frames = clip->num_frames, feet = contacts.num_feet(), bodies = clip->num_bodies;
  std::vector<Eigen::Vector2d> horizontal(frames, Eigen::Vector2d::Zero());
  for (int f = 0; f + 1 < frames; ++f) {
    Eigen::Vector2d error_sum = Eigen::Vector2d::Zero();
    double weight_sum = 0;
    for (int i = 0; i < feet; ++i) {
      const double height =
          std::max(timing.Lerp(contacts.foot_height, f, feet, i), timing.Lerp(contacts.foot_height, f + 1, feet, i));
      const double speed = std::max(timing.Lerp(contacts.foot_speed, f, feet, i) * timing.rate[f],
                                    timing.Lerp(contacts.foot_speed, f + 1, feet, i) * timing.rate[f + 1]);
      const double weight = std::clamp((2 * kFootContactHeight - height) / kFootContactHeight, 0.0, 1.0) *
                            std::clamp((2 * kPlantedFootSpeed - speed) / kPlantedFootSpeed, 0.0, 1.0);
      if (weight <= 0) continue;
      const int body = contacts.feet[i];
      const Eigen::Vector2d variant_step =
          (clip->body_pos[(f + 1) * bodies + body] - clip->body_pos[f * bodies + body]).head<2>();
      const Eigen::Vector2d parent_step =
          timing.Lerp(contacts.foot_xy, f + 1, feet, i) - timing.Lerp(contacts.foot_xy, f, feet, i);
      error_sum += weight * (variant_step - parent_step);
      weight_sum += weight;
    }
    horizontal[f + 1] = horizontal[f] - error_sum / std::max(weight_sum, 1.0);
  }

  std::vector<double> exact(frames);
  for (int f = 0; f < frames; ++f) exact[f] = timing.Lerp(contacts.lowest, f) - LowestGeomPoint(spec, *clip, f);
  static constexpr double kTaps[5] = {1 / 16.0, 4 / 16.0, 6 / 16.0, 4 / 16.0, 1 / 16.0};
  for (int f = 0; f < frames; ++f) {
    double smooth = 0;
    for (int k = -2; k <= 2; ++k) smooth += kTaps[k + 2] * exact[std::clamp(f + k, 0, frames - 1)];
    clip->root_pos[f].head<2>() += horizontal[f];
    clip->root_pos[f].z() += std::clamp(smooth, exact[f] - kGroundSmoothingSlack, exact[f] + kGroundSmoothingSlack);
  }
  return ComputeClipKinematics(spec, clip);
}

// Contact-aware attenuation: frames where a foot is on the floor and slides faster than
// kSkateTolerance plus the parent foot's speed if that is on the floor at that time too (a
// swinging foot that the variant lowers onto the floor drags). Either displaced leg may be the
// cause (the stance leg through the ground correction of the root), so all of them are attenuated.
std::vector<int> SlidingFrames(const HumanoidSpec& spec, const ParentContacts& contacts, const Timing& timing,
                               const MotionClip& clip) {
  std::vector<int> sliding;
  const int feet = contacts.num_feet();
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int i = 0; i < feet; ++i) {
      const int body = contacts.feet[i];
      if (BodyGeomBottom(spec, clip, f, body) >= kFootContactHeight) continue;
      const double speed = clip.body_vel[f * clip.num_bodies + body].head<2>().norm();
      // The parent's own sliding is allowed where its foot is on the floor too.
      const double parent_speed = timing.Lerp(contacts.foot_height, f, feet, i) < kFootContactHeight
                                      ? timing.Lerp(contacts.foot_speed, f, feet, i) * timing.rate[f]
                                      : 0.0;
      if (speed > parent_speed + kSkateTolerance) {
        sliding.push_back(f);
        break;
      }
    }
  }
  return sliding;
}

// Scales a leg's displacement gain down by up to half around each sliding frame (raised-cosine
// window), so the gain stays smooth.
void Attenuate(const std::vector<int>& sliding_frames, int half_width, std::vector<double>* gain) {
  const int frames = static_cast<int>(gain->size());
  std::vector<double> factor(frames, 1.0);
  for (int center : sliding_frames) {
    for (int k = -half_width; k <= half_width; ++k) {
      const int f = center + k;
      if (f < 0 || f >= frames) continue;
      const double bump = 0.5 * (1.0 + std::cos(M_PI * k / (half_width + 1)));
      factor[f] = std::min(factor[f], 1.0 - 0.5 * bump);
    }
  }
  for (int f = 0; f < frames; ++f) (*gain)[f] *= factor[f];
}

// Which bodies a variant displaces (every joint, or the part's joints; never the root), the limb
// of each body, and the displaced legs (which get the contact handling).
struct DisplacementPlan {
  std::vector<bool> displaced;
  std::vector<int> limb;
  std::vector<int> displaced_legs;
};

DisplacementPlan PlanDisplacement(const HumanoidSpec& spec, const PartLayout& layout, int part) {
  const int bodies = spec.num_bodies();
  const bool whole_body = part < 0;
  DisplacementPlan plan;
  plan.displaced.assign(bodies, whole_body);
  plan.displaced[0] = false;
  if (!whole_body) {
    for (int body : layout.parts[part].bodies) plan.displaced[body] = body != 0;
  }
  // Each body's limb: its ancestor among the root's children (L_Hip, R_Hip, Torso); -1 for the root.
  plan.limb.assign(bodies, -1);
  for (int b = 1; b < bodies; ++b) plan.limb[b] = spec.body(b).parent == 0 ? b : plan.limb[spec.body(b).parent];
  // The displaced legs: limbs with a foot below a displaced body. A variant with any gets the
  // contact handling.
  for (int foot : FootBodies(spec)) {
    bool moved = false;
    for (int b = foot; b > 0; b = spec.body(b).parent) moved = moved || plan.displaced[b];
    if (moved && std::find(plan.displaced_legs.begin(), plan.displaced_legs.end(), plan.limb[foot]) ==
                     plan.displaced_legs.end()) {
      plan.displaced_legs.push_back(plan.limb[foot]);
    }
  }
  return plan;
}

// The random curves of one variant. Every curve is drawn whatever the part, so that the streams
// do not depend on it.
struct VariantCurves {
  std::vector<double> warp_knots;
  std::vector<std::vector<Vec3>> displacement_knots;  // per body
};

VariantCurves DrawCurves(const VariantOptions& options, int bodies, int k) {
  VariantRng rng(options.seed, static_cast<uint64_t>(k));
  VariantCurves curves;
  curves.warp_knots.resize(options.knots);
  for (double& w : curves.warp_knots) w = rng.Uniform(-1.0, 1.0);
  curves.displacement_knots.resize(bodies);
  for (int b = 1; b < bodies; ++b) {
    curves.displacement_knots[b].resize(options.knots);
    for (Vec3& knot : curves.displacement_knots[b]) knot = RandomDisplacementKnot(rng, options.rotation_amplitude);
  }
  return curves;
}

// The parent time of each variant frame: warped, or the parent's own frame times.
Timing VariantTiming(const MotionClip& parent, double warp_amplitude, const std::vector<double>& warp_knots) {
  std::vector<double> source_time;
  if (warp_amplitude > 0) {
    source_time = WarpedSourceTimes(parent, warp_amplitude, warp_knots);
  } else {
    source_time.resize(parent.num_frames);
    for (int f = 0; f < parent.num_frames; ++f) source_time[f] = f / parent.fps;
  }
  return Timing(parent, std::move(source_time));
}

// The parent resampled at phi (the parent time of each frame). Without a warp the parent's
// frames are copied as they are (no interpolation), so that undisplaced bodies stay
// bit-identical.
MotionClip ResampledBase(const MotionClip& parent, const VariantOptions& options, const std::string& token, int k,
                         int bodies, bool warped, const Timing& timing) {
  MotionClip base;
  base.name = absl::StrCat(parent.name, "~", token, "~", k);
  base.label = parent.label;
  base.humanml3d_id = parent.humanml3d_id;
  base.source = absl::StrCat("generated from ", parent.name, " by ", kBuiltinVariantGenerator, " (part ", token,
                             ", seed ", options.seed, ")");
  base.fps = parent.fps;
  base.num_bodies = bodies;
  base.num_frames = timing.num_frames();
  if (warped) {
    base.root_pos.resize(base.num_frames);
    base.local_rot.resize(static_cast<size_t>(base.num_frames) * bodies);
    for (int f = 0; f < base.num_frames; ++f) {
      base.root_pos[f] = timing.Lerp(parent.root_pos, f);
      for (int b = 0; b < bodies; ++b) {
        base.local(f, b) = parent.local(timing.f0[f], b).slerp(timing.alpha[f], parent.local(timing.f0[f] + 1, b));
        base.local(f, b).normalize();
      }
    }
  } else {
    base.root_pos = parent.root_pos;
    base.local_rot = parent.local_rot;
  }
  return base;
}

// d(phase) per frame and displaced body.
std::vector<Vec3> Displacements(const MotionClip& parent, const DisplacementPlan& plan, const VariantCurves& curves,
                                const Timing& timing, int bodies) {
  const double duration = parent.duration();
  const int frames = timing.num_frames();
  std::vector<Vec3> displacement(static_cast<size_t>(frames) * bodies, Vec3::Zero());
  for (int f = 0; f < frames; ++f) {
    for (int b = 1; b < bodies; ++b) {
      if (plan.displaced[b]) {
        displacement[f * bodies + b] = EvaluateKnots(curves.displacement_knots[b], timing.source_time[f] / duration);
      }
    }
  }
  return displacement;
}

// q' = q * exp(g d), back inside the hinge ranges, then the contact handling; the per-limb
// gains g start at 1 and shrink where a displaced leg makes a foot slide.
absl::StatusOr<MotionClip> DisplaceWithContacts(const HumanoidSpec& spec, const DisplacementPlan& plan,
                                                const std::optional<ParentContacts>& contacts, const Timing& timing,
                                                const MotionClip& base, const std::vector<Vec3>& displacement,
                                                int attenuation_half_width) {
  const int bodies = spec.num_bodies();
  std::vector<std::vector<double>> gain(bodies, std::vector<double>(base.num_frames, 1.0));
  MotionClip clip;
  for (int round = 0;; ++round) {
    clip = base;
    for (int f = 0; f < clip.num_frames; ++f) {
      for (int b = 1; b < bodies; ++b) {
        if (!plan.displaced[b]) continue;
        const Vec3 d = gain[plan.limb[b]][f] * displacement[f * bodies + b];
        clip.local(f, b) = ClampToHingeRanges(spec.body(b), clip.local(f, b) * QuatFromRotationVector(d));
      }
    }
    if (auto status = ComputeClipKinematics(spec, &clip); !status.ok()) return status;
    if (!contacts) break;
    if (auto status = AnchorToParentContacts(spec, *contacts, timing, &clip); !status.ok()) return status;
    if (round == kMaxAttenuationRounds) break;
    const std::vector<int> sliding = SlidingFrames(spec, *contacts, timing, clip);
    if (sliding.empty()) break;
    for (int leg : plan.displaced_legs) Attenuate(sliding, attenuation_half_width, &gain[leg]);
  }
  return clip;
}

}  // namespace

absl::StatusOr<std::vector<MotionVariant>> GenerateVariants(const HumanoidSpec& spec, const PartLayout& layout,
                                                           const MotionClip& parent, const VariantOptions& options) {
  if (auto status = ValidateOptions(spec, layout, parent, options); !status.ok()) return status;
  const int bodies = spec.num_bodies();
  const bool whole_body = options.part < 0;
  const std::string token = whole_body ? "w" : layout.parts[options.part].name;
  const DisplacementPlan plan = PlanDisplacement(spec, layout, options.part);
  std::optional<ParentContacts> contacts;
  if (!plan.displaced_legs.empty()) contacts.emplace(spec, parent);
  const double warp_amplitude = whole_body ? options.time_warp_amplitude : 0.0;
  const int attenuation_half_width = std::max(1, static_cast<int>(std::lround(kAttenuationHalfWidth * parent.fps)));

  std::vector<MotionVariant> variants;
  variants.reserve(options.count);
  for (int k = 0; k < options.count; ++k) {
    const VariantCurves curves = DrawCurves(options, bodies, k);
    const Timing timing = VariantTiming(parent, warp_amplitude, curves.warp_knots);
    const MotionClip base = ResampledBase(parent, options, token, k, bodies, warp_amplitude > 0, timing);
    const std::vector<Vec3> displacement = Displacements(parent, plan, curves, timing, bodies);
    auto clip = DisplaceWithContacts(spec, plan, contacts, timing, base, displacement, attenuation_half_width);
    if (!clip.ok()) return clip.status();

    MotionVariant variant;
    variant.clip = *std::move(clip);
    variant.provenance.parent = parent.name;
    variant.provenance.generator = kBuiltinVariantGenerator;
    variant.provenance.part = options.part;
    variant.provenance.seed = options.seed;
    variants.push_back(std::move(variant));
  }
  return variants;
}

}  // namespace modskill
