#include "server/core/motion/motion_turn.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/core/motion/clip_fits_skeleton.h"
#include "server/core/motion/clip_name.h"

namespace modskill {
namespace {

Quat Yaw(double angle) { return Quat(Eigen::AngleAxisd(angle, Vec3::UnitZ())); }

absl::Status CheckRequest(const HumanoidSpec& spec, const MotionClip& base, const TurnRequest& request) {
  if (auto status = ValidateClipName(request.name, DefaultResourceLimits().max_name_length, "turn name");
      !status.ok()) {
    return status;
  }
  if (auto fits = CheckClipFitsSkeleton(spec, base, "turn"); !fits.ok()) return fits;
  if (!(std::abs(request.yaw_rate) <= kMaxTurnRate)) {
    return absl::InvalidArgumentError(absl::StrFormat("turn: yaw rate %g rad/s is not finite within +-%.4f rad/s",
                                                      request.yaw_rate, kMaxTurnRate));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<MotionClip> TurnClip(const HumanoidSpec& spec, const MotionClip& base, const TurnRequest& request) {
  if (auto status = CheckRequest(spec, base, request); !status.ok()) return status;
  MotionClip out;
  out.name = request.name;
  out.label = request.label.empty() ? absl::StrFormat("%s, turning %+.0f deg/s", base.label.empty() ? base.name : base.label,
                                                      request.yaw_rate * 180.0 / M_PI)
                                    : request.label;
  out.source = absl::StrCat("turned: ", base.name, " (", base.source, ")");
  out.fps = base.fps;
  out.num_frames = base.num_frames;
  out.num_bodies = base.num_bodies;
  out.root_pos = base.root_pos;
  out.local_rot = base.local_rot;
  const double per_frame = request.yaw_rate / base.fps;
  for (int f = 1; f < out.num_frames; ++f) {
    // The step from frame f-1 to f turned by the heading midway through it.
    Vec3 step = base.root_pos[f] - base.root_pos[f - 1];
    step.z() = 0;
    out.root_pos[f] = out.root_pos[f - 1] + Yaw(per_frame * (f - 0.5)) * step;
    out.root_pos[f].z() = base.root_pos[f].z();
    out.local(f, 0) = (Yaw(per_frame * f) * base.local(f, 0)).normalized();
  }
  if (auto status = ValidateClip(out); !status.ok()) return status;
  if (auto status = ComputeClipKinematics(spec, &out); !status.ok()) return status;
  return out;
}

}  // namespace modskill
