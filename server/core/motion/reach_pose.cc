#include "server/core/motion/reach_pose.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/core/motion/clip_fits_skeleton.h"
#include "server/core/motion/clip_name.h"
#include "server/core/motion/motion_splice.h"
#include "server/core/sim/heading_frame.h"
#include "server/core/sim/reach_ik.h"

namespace modskill {
namespace {

bool IsAncestorOrSelf(const HumanoidSpec& spec, int body, int of) {
  for (int b = of; b >= 0; b = spec.body(b).parent) {
    if (b == body) return true;
  }
  return false;
}

absl::Status CheckInputs(const HumanoidSpec& spec, const MotionClip& base, const ReachPoseRequest& request) {
  if (auto status = ValidateClipName(request.name, DefaultResourceLimits().max_name_length, "reach pose name");
      !status.ok()) {
    return status;
  }
  if (absl::Status fits = CheckClipFitsSkeleton(spec, base, "reach pose"); !fits.ok()) return fits;
  if (request.hand <= 0 || request.hand >= spec.num_bodies()) {
    return absl::InvalidArgumentError(absl::StrCat("reach pose: hand body index ", request.hand,
                                                   " is not a non-root body of the skeleton"));
  }
  if (request.moved_bodies.empty()) return absl::InvalidArgumentError("reach pose: no body is moved");
  for (int body : request.moved_bodies) {
    if (body <= 0 || body >= spec.num_bodies() || !IsAncestorOrSelf(spec, body, request.hand)) {
      const std::string name = body < 0 || body >= spec.num_bodies() ? absl::StrCat(body) : spec.body(body).name;
      return absl::InvalidArgumentError(absl::StrCat("reach pose: moved body '", name, "' is not '",
                                                     spec.body(request.hand).name, "' or a non-root ancestor of it"));
    }
  }
  if (!request.target.allFinite()) return absl::InvalidArgumentError("reach pose: the target is not finite");
  return absl::OkStatus();
}

// The world point the reach task means by `target` in frame `frame` (ReachTask::DrawGoal).
Vec3 WorldTarget(const MotionClip& clip, int frame, const Vec3& target) {
  return HeadingGroundPointToWorld(clip.root_pos[frame], clip.local(frame, 0), target);
}

}  // namespace

absl::StatusOr<ReachPose> MakeReachPose(const HumanoidSpec& spec, const MotionClip& base,
                                        const ReachPoseRequest& request) {
  if (auto status = CheckInputs(spec, base, request); !status.ok()) return status;
  MotionClip posed = base;
  if (auto status = ComputeClipKinematics(spec, &posed); !status.ok()) return status;
  const int held = std::min(static_cast<int>(std::lround(base.fps * kHoldRampSeconds)), base.num_frames - 1);
  const RootState root{posed.root_pos[held], posed.local(held, 0)};
  const std::vector<double> start(posed.dof_pos.begin() + held * spec.num_hinges(),
                                  posed.dof_pos.begin() + (held + 1) * spec.num_hinges());
  const ReachIkResult solved =
      SolveReachIk(spec, root, start, request.hand, request.moved_bodies, WorldTarget(posed, held, request.target));
  for (int f = 0; f < posed.num_frames; ++f) {
    const double weight = HoldRampWeight(posed.fps, f);
    for (int body : request.moved_bodies) {
      const double* angle = &solved.dof_pos[3 * (body - 1)];
      posed.local(f, body) = posed.local(f, body).slerp(weight, HingeRotation(angle[0], angle[1], angle[2])).normalized();
    }
  }
  posed.name = request.name;
  posed.label = request.label.empty()
                    ? absl::StrFormat("%s, %s held at (%.2f, %.2f, %.2f)", base.label.empty() ? base.name : base.label,
                                      spec.body(request.hand).name, request.target.x(), request.target.y(),
                                      request.target.z())
                    : request.label;
  posed.source = absl::StrCat("reach pose by inverse kinematics on ", base.name, " (", base.source, ")");
  if (auto status = ValidateClip(posed); !status.ok()) return status;
  if (auto status = PlaceOnGround(spec, &posed); !status.ok()) return status;
  const Vec3 hand = posed.body_pos[held * posed.num_bodies + request.hand];
  const double distance = (hand - WorldTarget(posed, held, request.target)).norm();
  return ReachPose{std::move(posed), distance};
}

}  // namespace modskill
