#include "server/core/curriculum/plausibility_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace modskill {
namespace {

PlausibilityVerdict Reject(std::string reason) { return PlausibilityVerdict{false, std::move(reason)}; }

double HingeViolation(const HumanoidSpec& spec, const MotionClip& clip, int frame, int hinge) {
  const BodySpec& body = spec.body(1 + hinge / 3);
  const double angle = clip.dof_pos[frame * clip.num_hinges() + hinge];
  if (!std::isfinite(angle)) return std::numeric_limits<double>::infinity();
  return std::max(body.range_low[hinge % 3] - angle, angle - body.range_high[hinge % 3]);
}

// slack[h]: how far hinge h may leave its range.
std::optional<PlausibilityVerdict> CheckJointLimits(const HumanoidSpec& spec, const MotionClip& clip,
                                                    const std::vector<double>& slack) {
  const int hinges = clip.num_hinges();
  double worst = 0, worst_slack = 0;
  int worst_frame = -1, worst_hinge = -1;
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int h = 0; h < hinges; ++h) {
      const double excess = HingeViolation(spec, clip, f, h) - slack[h];
      if (excess > worst || std::isnan(excess)) {
        worst = std::isnan(excess) ? std::numeric_limits<double>::infinity() : excess;
        worst_slack = slack[h];
        worst_frame = f;
        worst_hinge = h;
      }
    }
  }
  if (worst_hinge < 0) return std::nullopt;
  const double slack_used = worst_slack;
  worst += slack_used;
  const BodySpec& body = spec.body(1 + worst_hinge / 3);
  const int axis = worst_hinge % 3;
  return Reject(absl::StrFormat("joint_limit: %s_%c = %.3f rad outside [%.3f, %.3f] by %.3f rad (> %.3f) at frame %d",
                                body.name, "xyz"[axis], clip.dof_pos[worst_frame * hinges + worst_hinge],
                                body.range_low[axis], body.range_high[axis], worst, slack_used, worst_frame));
}

// Where a per-body, per-frame quantity is largest, if it exceeds `above` anywhere: the first
// place it reaches its maximum, or the last non-finite value (taken as infinite); body -1 when
// it never exceeds `above`.
struct Extreme {
  double value;
  int frame = -1;
  int body = -1;
};

// Depth below the floor of the lowest geometry point, over bodies and frames.
Extreme DeepestPoint(const HumanoidSpec& spec, const MotionClip& clip, double above) {
  Extreme deepest{above};
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int b = 0; b < clip.num_bodies; ++b) {
      const double depth = -BodyGeomBottom(spec, clip, f, b);
      if (depth > deepest.value || !std::isfinite(depth)) {
        deepest = {std::isfinite(depth) ? depth : std::numeric_limits<double>::infinity(), f, b};
      }
    }
  }
  return deepest;
}

// Frame-to-frame speed |body_pos[f + 1] - body_pos[f]| * fps, over bodies and frames f.
Extreme FastestMove(const MotionClip& clip, double above) {
  Extreme fastest{above};
  for (int f = 0; f + 1 < clip.num_frames; ++f) {
    for (int b = 0; b < clip.num_bodies; ++b) {
      const double speed =
          (clip.body_pos[(f + 1) * clip.num_bodies + b] - clip.body_pos[f * clip.num_bodies + b]).norm() * clip.fps;
      if (speed > fastest.value || !std::isfinite(speed)) {
        fastest = {std::isfinite(speed) ? speed : std::numeric_limits<double>::infinity(), f, b};
      }
    }
  }
  return fastest;
}

// One foot's horizontal speed over the frames where its geometry touches the floor.
struct FootSkate {
  int body;
  double median;
  int contact_frames;
  double fastest;
  int fastest_frame;
};

// Every foot that touches the floor at least once, in FootBodies order.
std::vector<FootSkate> FootSkates(const HumanoidSpec& spec, const MotionClip& clip) {
  std::vector<FootSkate> feet;
  std::vector<double> speeds;
  for (int b : FootBodies(spec)) {
    speeds.clear();
    int fastest_frame = -1;
    double fastest = -1;
    for (int f = 0; f < clip.num_frames; ++f) {
      if (BodyGeomBottom(spec, clip, f, b) >= kFootContactHeight) continue;
      const double speed = clip.body_vel[f * clip.num_bodies + b].head<2>().norm();
      speeds.push_back(speed);
      if (speed > fastest) {
        fastest = speed;
        fastest_frame = f;
      }
    }
    // A plant lasts more than one frame; a foot near the floor for a single frame is a swing
    // passing by (the walk's R_Leg variants brush it at 3.5 m/s), not a slide.
    if (speeds.size() < kMinPlantFrames) continue;
    const size_t mid = speeds.size() / 2;
    std::nth_element(speeds.begin(), speeds.begin() + mid, speeds.end());
    feet.push_back({b, speeds[mid], static_cast<int>(speeds.size()), fastest, fastest_frame});
  }
  return feet;
}

std::optional<PlausibilityVerdict> CheckPenetration(const HumanoidSpec& spec, const MotionClip& clip,
                                                    double max_penetration) {
  const Extreme deepest = DeepestPoint(spec, clip, max_penetration);
  if (deepest.body < 0) return std::nullopt;
  return Reject(absl::StrFormat("penetration: %s reaches %.3f m below the floor (> %.3f) at frame %d",
                                spec.body(deepest.body).name, deepest.value, max_penetration, deepest.frame));
}

std::optional<PlausibilityVerdict> CheckBodySpeed(const HumanoidSpec& spec, const MotionClip& clip, double max_speed) {
  const Extreme fastest = FastestMove(clip, max_speed);
  if (fastest.body < 0) return std::nullopt;
  return Reject(absl::StrFormat("body_speed: %s moves at %.2f m/s (> %.2f) between frames %d and %d",
                                spec.body(fastest.body).name, fastest.value, max_speed, fastest.frame,
                                fastest.frame + 1));
}

std::optional<PlausibilityVerdict> CheckFootSkate(const HumanoidSpec& spec, const MotionClip& clip,
                                                  double max_skate) {
  for (const FootSkate& foot : FootSkates(spec, clip)) {
    if (foot.median > max_skate) {
      return Reject(absl::StrFormat(
          "foot_skate: %s slides at a median %.2f m/s (> %.2f) over its %d contact frames, "
          "fastest %.2f m/s at frame %d",
          spec.body(foot.body).name, foot.median, max_skate, foot.contact_frames, foot.fastest, foot.fastest_frame));
    }
  }
  return std::nullopt;
}

// The largest median contact-frame speed over the feet (0 when no foot touches the floor).
double WorstFootSkate(const HumanoidSpec& spec, const MotionClip& clip) {
  double worst = 0;
  for (const FootSkate& foot : FootSkates(spec, clip)) worst = std::max(worst, foot.median);
  return worst;
}

// The clip itself, or a copy with its kinematics computed; null (with *reason) when it cannot be.
const MotionClip* WithKinematics(const HumanoidSpec& spec, const MotionClip& clip, MotionClip* storage,
                                 std::string* reason) {
  if (clip.num_bodies != spec.num_bodies()) {
    *reason = absl::StrCat("invalid: clip '", clip.name, "' has ", clip.num_bodies, " bodies, the skeleton ",
                           spec.num_bodies());
    return nullptr;
  }
  const size_t rows = static_cast<size_t>(clip.num_frames) * clip.num_bodies;
  const bool has_kinematics = clip.num_frames >= 2 && clip.body_pos.size() == rows && clip.body_rot.size() == rows &&
                              clip.body_vel.size() == rows &&
                              clip.dof_pos.size() == static_cast<size_t>(clip.num_frames) * clip.num_hinges();
  if (has_kinematics) return &clip;
  *storage = clip;
  if (auto status = ComputeClipKinematics(spec, storage); !status.ok()) {
    *reason = absl::StrCat("invalid: ", status.message());
    return nullptr;
  }
  return storage;
}

std::optional<PlausibilityVerdict> CheckDiscriminator(const std::vector<float>& scores, double min_score);

PlausibilityVerdict RunChecks(const HumanoidSpec& spec, const MotionClip& clip, const PlausibilityOptions& options,
                              const std::vector<double>& hinge_slack, const std::vector<float>* discriminator_scores) {
  if (auto verdict = CheckJointLimits(spec, clip, hinge_slack)) return *verdict;
  if (auto verdict = CheckPenetration(spec, clip, options.max_penetration)) return *verdict;
  if (auto verdict = CheckBodySpeed(spec, clip, options.max_body_speed)) return *verdict;
  if (auto verdict = CheckFootSkate(spec, clip, options.max_foot_skate)) return *verdict;
  if (discriminator_scores != nullptr) {
    if (auto verdict = CheckDiscriminator(*discriminator_scores, options.min_discriminator_score)) return *verdict;
  }
  return PlausibilityVerdict{true, ""};
}

std::optional<PlausibilityVerdict> CheckDiscriminator(const std::vector<float>& scores, double min_score) {
  if (scores.empty()) return Reject("discriminator: no scores given");
  double sum = 0;
  int lowest = 0;
  for (size_t i = 0; i < scores.size(); ++i) {
    const float s = scores[i];
    if (!std::isfinite(s) || s < 0 || s > 1) {
      return Reject(absl::StrFormat("discriminator: score %g of sample %d outside [0, 1]", s, static_cast<int>(i)));
    }
    sum += s;
    if (s < scores[lowest]) lowest = static_cast<int>(i);
  }
  const double mean = sum / scores.size();
  if (mean >= min_score) return std::nullopt;
  return Reject(absl::StrFormat(
      "discriminator: mean score %.3f over %d sampled frames (< %.3f), lowest %.3f at sample %d", mean,
      static_cast<int>(scores.size()), min_score, scores[lowest], lowest));
}

}  // namespace

double BodyGeomBottom(const HumanoidSpec& spec, const MotionClip& clip, int frame, int body) {
  const int i = frame * clip.num_bodies + body;
  return spec.body(body).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]);
}

PlausibilityVerdict CheckPlausibility(const HumanoidSpec& spec, const MotionClip& clip,
                                      const PlausibilityOptions& options,
                                      const std::vector<float>* discriminator_scores) {
  MotionClip storage;
  std::string reason;
  const MotionClip* checked = WithKinematics(spec, clip, &storage, &reason);
  if (checked == nullptr) return Reject(reason);
  return RunChecks(spec, *checked, options, std::vector<double>(clip.num_hinges(), options.max_limit_violation),
                   discriminator_scores);
}

PlausibilityVerdict CheckVariantPlausibility(const HumanoidSpec& spec, const MotionClip& variant,
                                             const MotionClip& parent, const PlausibilityOptions& options,
                                             const std::vector<float>* discriminator_scores) {
  MotionClip variant_storage, parent_storage;
  std::string reason;
  const MotionClip* checked = WithKinematics(spec, variant, &variant_storage, &reason);
  if (checked == nullptr) return Reject(reason);
  const MotionClip* reference = WithKinematics(spec, parent, &parent_storage, &reason);
  if (reference == nullptr) return Reject(absl::StrCat("invalid: the parent: ", reason));
  // The parent's own defects are allowed, plus the absolute margins on top of them.
  std::vector<double> hinge_slack(checked->num_hinges(), 0.0);
  for (int h = 0; h < checked->num_hinges(); ++h) {
    double parent_violation = 0;
    for (int f = 0; f < reference->num_frames; ++f) {
      parent_violation = std::max(parent_violation, HingeViolation(spec, *reference, f, h));
    }
    hinge_slack[h] = std::min(parent_violation, 10.0) + options.max_limit_violation;
  }
  PlausibilityOptions relative = options;
  relative.max_penetration = std::max(options.max_penetration, DeepestPoint(spec, *reference, 0.0).value + 0.01);
  relative.max_body_speed = std::max(options.max_body_speed, 1.25 * FastestMove(*reference, 0.0).value);
  relative.max_foot_skate = std::max(options.max_foot_skate, 1.25 * WorstFootSkate(spec, *reference));
  return RunChecks(spec, *checked, relative, hinge_slack, discriminator_scores);
}

}  // namespace modskill
