#include "server/core/motion/motion_clip.h"

#include "server/core/motion/floor_height.h"
#include "server/core/motion/stance_feet.h"
#include "server/core/sim/body_kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

bool Finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

}  // namespace

absl::Status ValidateClipTiming(double fps, int64_t num_frames, absl::string_view field, const ResourceLimits& limits) {
  if (!(std::isfinite(fps) && fps > 0 && fps <= limits.max_fps)) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": frame rate ", fps, " fps outside (0, ", limits.max_fps, "] (max_fps)"));
  }
  if (num_frames > limits.max_clip_frames) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": ", num_frames, " frames, more than the limit of ",
                                                   limits.max_clip_frames, " (max_clip_frames)"));
  }
  // In double: a rate near zero gives a duration no integer holds.
  const double seconds = num_frames > 1 ? (num_frames - 1) / fps : 0.0;
  if (!(seconds <= limits.max_clip_seconds)) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": ", num_frames, " frames at ", fps, " fps last ", seconds,
                                                   " s, more than the limit of ", limits.max_clip_seconds,
                                                   " s (max_clip_seconds)"));
  }
  return absl::OkStatus();
}

absl::Status ValidateClip(const MotionClip& clip, const ResourceLimits& limits) {
  const std::string where = absl::StrCat("clip '", clip.name, "'");
  if (clip.num_frames < 2) return absl::InvalidArgumentError(absl::StrCat(where, ": num_frames ", clip.num_frames, " < 2"));
  if (auto status = ValidateClipTiming(clip.fps, clip.num_frames, absl::StrCat(where, ": fps"), limits); !status.ok()) {
    return status;
  }
  if (clip.num_bodies < 1) return absl::InvalidArgumentError(absl::StrCat(where, ": num_bodies ", clip.num_bodies));
  if (clip.root_pos.size() != static_cast<size_t>(clip.num_frames)) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": root_pos has ", clip.root_pos.size(), " rows, expected ",
                                                   clip.num_frames));
  }
  if (clip.local_rot.size() != static_cast<size_t>(clip.num_frames) * clip.num_bodies) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": local_rot has ", clip.local_rot.size(), " entries, expected ",
                                                   clip.num_frames * clip.num_bodies));
  }
  for (int f = 0; f < clip.num_frames; ++f) {
    if (!Finite(clip.root_pos[f])) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": root_pos of frame ", f, " is not finite"));
    }
    if (clip.root_pos[f].cwiseAbs().maxCoeff() > limits.max_position) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": root_pos of frame ", f, " (", clip.root_pos[f].x(), ", ",
                                                     clip.root_pos[f].y(), ", ", clip.root_pos[f].z(),
                                                     ") is more than ", limits.max_position,
                                                     " m from the origin (max_position)"));
    }
    for (int b = 0; b < clip.num_bodies; ++b) {
      const Quat& q = clip.local(f, b);
      if (!std::isfinite(q.w()) || !Finite(q.vec())) {
        return absl::InvalidArgumentError(absl::StrCat(where, ": rotation of body ", b, " in frame ", f, " is not finite"));
      }
      if (std::abs(q.norm() - 1.0) > 1e-3) {
        return absl::InvalidArgumentError(absl::StrCat(where, ": rotation of body ", b, " in frame ", f,
                                                       " is not a unit quaternion (norm ", q.norm(), ")"));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status ComputeClipKinematics(const HumanoidSpec& spec, MotionClip* clip) {
  if (clip->num_bodies != spec.num_bodies()) {
    return absl::InvalidArgumentError(absl::StrCat("clip '", clip->name, "': ", clip->num_bodies,
                                                   " bodies but the skeleton has ", spec.num_bodies()));
  }
  if (auto status = ValidateClip(*clip); !status.ok()) return status;
  const int frames = clip->num_frames, bodies = clip->num_bodies, hinges = clip->num_hinges();
  clip->body_pos.assign(frames * bodies, Vec3::Zero());
  clip->body_rot.assign(frames * bodies, Quat::Identity());
  clip->body_vel.assign(frames * bodies, Vec3::Zero());
  clip->body_ang_vel.assign(frames * bodies, Vec3::Zero());
  clip->dof_pos.assign(frames * hinges, 0.0);
  clip->dof_vel.assign(frames * hinges, 0.0);
  for (int f = 0; f < frames; ++f) {
    for (int b = 1; b < bodies; ++b) {
      const Vec3 angles = HingeAngles(clip->local(f, b));
      for (int a = 0; a < 3; ++a) clip->dof_pos[f * hinges + 3 * (b - 1) + a] = angles[a];
    }
  }
  // Root velocities and hinge rates from central differences (one-sided at the ends); every
  // other body's velocity is propagated from them exactly as MuJoCo does, so a simulation set
  // to a frame reports the reference's own velocities.
  const double dt = 1.0 / clip->fps;
  for (int f = 0; f < frames; ++f) {
    const int f0 = std::max(0, f - 1), f1 = std::min(frames - 1, f + 1);
    const double span = (f1 - f0) * dt;
    for (int h = 0; h < hinges; ++h) {
      clip->dof_vel[f * hinges + h] = WrapAngle(clip->dof_pos[f1 * hinges + h] - clip->dof_pos[f0 * hinges + h]) / span;
    }
    RootState root;
    root.pos = clip->root_pos[f];
    root.rot = clip->local(f, 0).normalized();
    root.vel = (clip->root_pos[f1] - clip->root_pos[f0]) / span;
    root.ang_vel = AngularVelocity(clip->local(f0, 0).normalized(), clip->local(f1, 0).normalized(), span);
    const int r = f * bodies;
    ComputeBodyKinematics(spec, root, &clip->dof_pos[f * hinges], &clip->dof_vel[f * hinges], &clip->body_pos[r],
                          &clip->body_rot[r], &clip->body_vel[r], &clip->body_ang_vel[r]);
  }
  return absl::OkStatus();
}

absl::StatusOr<MotionClip> ResampleClip(const MotionClip& clip, double fps, const ResourceLimits& limits) {
  if (auto status = ValidateClip(clip, limits); !status.ok()) return status;
  // The output's size from the duration: the rate is checked first, so that the count, bounded by
  // max_clip_seconds x max_fps, is finite before it is cast and checked against max_clip_frames.
  const std::string field = absl::StrCat("clip '", clip.name, "' resampled to ", fps, " fps");
  if (auto status = ValidateClipTiming(fps, 2, field, limits); !status.ok()) return status;
  const double frames = std::floor(clip.duration() * fps + 1e-6) + 1;
  if (auto status = ValidateClipTiming(fps, static_cast<int64_t>(frames), field, limits); !status.ok()) return status;
  MotionClip out;
  out.name = clip.name;
  out.label = clip.label;
  out.humanml3d_id = clip.humanml3d_id;
  out.source = clip.source;
  out.num_bodies = clip.num_bodies;
  out.fps = fps;
  out.num_frames = std::max(2, static_cast<int>(frames));
  out.root_pos.resize(out.num_frames);
  out.local_rot.resize(static_cast<size_t>(out.num_frames) * out.num_bodies);
  for (int f = 0; f < out.num_frames; ++f) {
    const double source_frame = std::min(f / fps * clip.fps, static_cast<double>(clip.num_frames - 1));
    const int f0 = std::min(static_cast<int>(source_frame), clip.num_frames - 2);
    const double alpha = source_frame - f0;
    out.root_pos[f] = (1 - alpha) * clip.root_pos[f0] + alpha * clip.root_pos[f0 + 1];
    for (int b = 0; b < clip.num_bodies; ++b) {
      out.local(f, b) = clip.local(f0, b).slerp(alpha, clip.local(f0 + 1, b)).normalized();
    }
  }
  return out;
}

double LowestGeomPoint(const HumanoidSpec& spec, const MotionClip& clip, int frame) {
  double lowest = std::numeric_limits<double>::infinity();
  for (int b = 0; b < clip.num_bodies; ++b) {
    const int i = frame * clip.num_bodies + b;
    lowest = std::min(lowest, spec.body(b).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]));
  }
  return lowest;
}

absl::Status PlaceOnGround(const HumanoidSpec& spec, MotionClip* clip, FloorMode mode) {
  if (auto status = ComputeClipKinematics(spec, clip); !status.ok()) return status;
  std::vector<double> lowest(clip->num_frames);
  for (int f = 0; f < clip->num_frames; ++f) lowest[f] = LowestGeomPoint(spec, *clip, f);
  // The floor follows the clip, never above a frame's lowest point (floor_height.h): one
  // constant shift leaves stretches of a retargeted clip floating.
  std::vector<double> floor = FloorHeights(lowest, clip->fps);
  if (mode == FloorMode::kStance) floor = PinFloorToStance(floor, lowest, StanceFrames(spec, *clip, floor, lowest));
  for (int f = 0; f < clip->num_frames; ++f) clip->root_pos[f].z() -= floor[f];
  return ComputeClipKinematics(spec, clip);
}

double FootContactRatio(const HumanoidSpec& spec, const MotionClip& clip, double threshold) {
  if (clip.body_pos.empty() || clip.num_frames == 0) return 0.0;
  std::vector<int> feet;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    if (absl::StrContains(spec.body(b).name, "Ankle") || absl::StrContains(spec.body(b).name, "Toe")) feet.push_back(b);
  }
  int in_contact = 0;
  for (int f = 0; f < clip.num_frames; ++f) {
    for (int b : feet) {
      const int i = f * clip.num_bodies + b;
      if (spec.body(b).geom.LowestPoint(clip.body_pos[i], clip.body_rot[i]) < threshold) {
        ++in_contact;
        break;
      }
    }
  }
  return static_cast<double>(in_contact) / clip.num_frames;
}

}  // namespace modskill
