#include "server/core/plausibility_filter.h"

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

std::optional<PlausibilityVerdict> CheckJointLimits(const HumanoidSpec& spec, const MotionClip& clip, double slack) {
  const int hinges = clip.num_hinges();
  double worst = slack;
  int worst_frame = -1, worst_hinge = -1;
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int h = 0; h < hinges; ++h) {
      const BodySpec& body = spec.body(1 + h / 3);
      const double angle = clip.dof_pos[f * hinges + h];
      const double violation = std::max(body.range_low[h % 3] - angle, angle - body.range_high[h % 3]);
      if (violation > worst || !std::isfinite(angle)) {
        worst = std::isfinite(angle) ? violation : std::numeric_limits<double>::infinity();
        worst_frame = f;
        worst_hinge = h;
      }
    }
  }
  if (worst_hinge < 0) return std::nullopt;
  const BodySpec& body = spec.body(1 + worst_hinge / 3);
  const int axis = worst_hinge % 3;
  return Reject(absl::StrFormat("joint_limit: %s_%c = %.3f rad outside [%.3f, %.3f] by %.3f rad (> %.3f) at frame %d",
                                body.name, "xyz"[axis], clip.dof_pos[worst_frame * hinges + worst_hinge],
                                body.range_low[axis], body.range_high[axis], worst, slack, worst_frame));
}

std::optional<PlausibilityVerdict> CheckPenetration(const HumanoidSpec& spec, const MotionClip& clip,
                                                    double max_penetration) {
  double lowest = -max_penetration;
  int lowest_frame = -1, lowest_body = -1;
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int b = 0; b < clip.num_bodies; ++b) {
      const int i = f * clip.num_bodies + b;
      const double bottom = spec.body(b).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]);
      if (bottom < lowest || !std::isfinite(bottom)) {
        lowest = std::isfinite(bottom) ? bottom : -std::numeric_limits<double>::infinity();
        lowest_frame = f;
        lowest_body = b;
      }
    }
  }
  if (lowest_body < 0) return std::nullopt;
  return Reject(absl::StrFormat("penetration: %s reaches %.3f m below the floor (> %.3f) at frame %d",
                                spec.body(lowest_body).name, -lowest, max_penetration, lowest_frame));
}

std::optional<PlausibilityVerdict> CheckBodySpeed(const HumanoidSpec& spec, const MotionClip& clip, double max_speed) {
  double fastest = max_speed;
  int fastest_frame = -1, fastest_body = -1;
  for (int f = 0; f + 1 < clip.num_frames; ++f) {
    for (int b = 0; b < clip.num_bodies; ++b) {
      const double speed =
          (clip.body_pos[(f + 1) * clip.num_bodies + b] - clip.body_pos[f * clip.num_bodies + b]).norm() * clip.fps;
      if (speed > fastest || !std::isfinite(speed)) {
        fastest = std::isfinite(speed) ? speed : std::numeric_limits<double>::infinity();
        fastest_frame = f;
        fastest_body = b;
      }
    }
  }
  if (fastest_body < 0) return std::nullopt;
  return Reject(absl::StrFormat("body_speed: %s moves at %.2f m/s (> %.2f) between frames %d and %d",
                                spec.body(fastest_body).name, fastest, max_speed, fastest_frame, fastest_frame + 1));
}

std::optional<PlausibilityVerdict> CheckFootSkate(const HumanoidSpec& spec, const MotionClip& clip,
                                                  double max_skate) {
  std::vector<double> speeds;
  for (int b : FootBodies(spec)) {
    const std::string& name = spec.body(b).name;
    speeds.clear();
    int fastest_frame = -1;
    double fastest = -1;
    for (int f = 0; f < clip.num_frames; ++f) {
      const int i = f * clip.num_bodies + b;
      if (spec.body(b).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]) >= kFootContactHeight) continue;
      const double speed = clip.body_vel[i].head<2>().norm();
      speeds.push_back(speed);
      if (speed > fastest) {
        fastest = speed;
        fastest_frame = f;
      }
    }
    if (speeds.empty()) continue;
    const size_t mid = speeds.size() / 2;
    std::nth_element(speeds.begin(), speeds.begin() + mid, speeds.end());
    const double median = speeds[mid];
    if (median > max_skate) {
      return Reject(absl::StrFormat(
          "foot_skate: %s slides at a median %.2f m/s (> %.2f) over its %d contact frames, "
          "fastest %.2f m/s at frame %d",
          name, median, max_skate, static_cast<int>(speeds.size()), fastest, fastest_frame));
    }
  }
  return std::nullopt;
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

std::vector<int> FootBodies(const HumanoidSpec& spec) {
  std::vector<int> feet;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    if (absl::StrContains(spec.body(b).name, "Ankle") || absl::StrContains(spec.body(b).name, "Toe")) feet.push_back(b);
  }
  return feet;
}

double BodyGeomBottom(const HumanoidSpec& spec, const MotionClip& clip, int frame, int body) {
  const int i = frame * clip.num_bodies + body;
  return spec.body(body).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]);
}

PlausibilityVerdict CheckPlausibility(const HumanoidSpec& spec, const MotionClip& clip,
                                      const PlausibilityOptions& options,
                                      const std::vector<float>* discriminator_scores) {
  if (clip.num_bodies != spec.num_bodies()) {
    return Reject(absl::StrCat("invalid: clip '", clip.name, "' has ", clip.num_bodies, " bodies, the skeleton ",
                               spec.num_bodies()));
  }
  const size_t rows = static_cast<size_t>(clip.num_frames) * clip.num_bodies;
  const bool has_kinematics = clip.num_frames >= 2 && clip.body_pos.size() == rows && clip.body_rot.size() == rows &&
                              clip.body_vel.size() == rows &&
                              clip.dof_pos.size() == static_cast<size_t>(clip.num_frames) * clip.num_hinges();
  MotionClip computed;
  const MotionClip* checked = &clip;
  if (!has_kinematics) {
    computed = clip;
    if (auto status = ComputeClipKinematics(spec, &computed); !status.ok()) {
      return Reject(absl::StrCat("invalid: ", status.message()));
    }
    checked = &computed;
  }
  if (auto verdict = CheckJointLimits(spec, *checked, options.max_limit_violation)) return *verdict;
  if (auto verdict = CheckPenetration(spec, *checked, options.max_penetration)) return *verdict;
  if (auto verdict = CheckBodySpeed(spec, *checked, options.max_body_speed)) return *verdict;
  if (auto verdict = CheckFootSkate(spec, *checked, options.max_foot_skate)) return *verdict;
  if (discriminator_scores != nullptr) {
    if (auto verdict = CheckDiscriminator(*discriminator_scores, options.min_discriminator_score)) return *verdict;
  }
  return PlausibilityVerdict{true, ""};
}

}  // namespace modskill
