#include "server/core/motion/motion_splice.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "server/core/motion/clip_fits_skeleton.h"
#include "server/core/motion/clip_name.h"

namespace modskill {
namespace {

// The source frame (fractional) that base frame `f` plays.
double SourceFrame(const MotionClip& base, const MotionClip& source, const SpliceRequest& request, int f) {
  const double last = source.num_frames - 1;
  switch (request.timing) {
    case SpliceTiming::kStretch:
      return base.num_frames > 1 ? f * last / (base.num_frames - 1) : 0.0;
    case SpliceTiming::kHold:
      return request.hold_at * last;
    case SpliceTiming::kClip:
      break;
  }
  return std::min(static_cast<double>(f), last);
}

// How much of the source's rotation frame `f` takes: all of it, except while a held pose is reached.
double SourceWeight(const MotionClip& base, const SpliceRequest& request, int f) {
  return request.timing == SpliceTiming::kHold ? HoldRampWeight(base.fps, f) : 1.0;
}

absl::Status CheckInputs(const HumanoidSpec& spec, const MotionClip& base, const MotionClip& source,
                         const SpliceRequest& request) {
  if (auto status = ValidateClipName(request.name, DefaultResourceLimits().max_name_length, "splice name");
      !status.ok()) {
    return status;
  }
  for (const MotionClip* clip : {&base, &source}) {
    if (absl::Status fits = CheckClipFitsSkeleton(spec, *clip, "splice"); !fits.ok()) return fits;
  }
  if (std::abs(base.fps - source.fps) > 1e-9) {
    return absl::InvalidArgumentError(absl::StrCat("splice: clip '", source.name, "' runs at ", source.fps,
                                                   " fps and '", base.name, "' at ", base.fps,
                                                   "; resample one first"));
  }
  if (request.source_bodies.empty()) return absl::InvalidArgumentError("splice: no body is taken from the source");
  if (!(request.hold_at >= 0 && request.hold_at <= 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("splice: hold_at ", request.hold_at, " is not a share of the source's duration in [0, 1]"));
  }
  for (int body : request.source_bodies) {
    if (body == 0) {
      return absl::InvalidArgumentError(absl::StrCat("splice: the root body '", spec.body(0).name,
                                                     "' keeps the base's travel and cannot come from the source"));
    }
    if (body < 0 || body >= spec.num_bodies()) {
      return absl::InvalidArgumentError(absl::StrCat("splice: body index ", body, " is not in the skeleton"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

double HoldRampWeight(double fps, int frame) {
  const double x = std::min(1.0, frame / (fps * kHoldRampSeconds));
  return x * x * (3.0 - 2.0 * x);
}

absl::StatusOr<SpliceTiming> ParseSpliceTiming(absl::string_view name) {
  if (name == "stretch") return SpliceTiming::kStretch;
  if (name == "clip") return SpliceTiming::kClip;
  if (name == "hold") return SpliceTiming::kHold;
  return absl::InvalidArgumentError(absl::StrCat("splice timing '", name, "' is not one of stretch, clip, hold"));
}

absl::StatusOr<MotionClip> SpliceParts(const HumanoidSpec& spec, const MotionClip& base, const MotionClip& source,
                                       const SpliceRequest& request) {
  if (auto status = CheckInputs(spec, base, source, request); !status.ok()) return status;
  MotionClip out;
  out.name = request.name;
  out.label = request.label;
  if (out.label.empty()) {
    std::vector<std::string> body_names;
    for (int body : request.source_bodies) body_names.push_back(spec.body(body).name);
    out.label = absl::StrCat(base.label.empty() ? base.name : base.label, ", with ", absl::StrJoin(body_names, ", "),
                             " from ", source.name);
  }
  out.source = absl::StrCat("spliced: ", base.name, " (", base.source, ") with ", source.name, " (", source.source,
                            ")");
  out.fps = base.fps;
  out.num_frames = base.num_frames;
  out.num_bodies = base.num_bodies;
  out.root_pos = base.root_pos;
  out.local_rot = base.local_rot;
  for (int f = 0; f < out.num_frames; ++f) {
    const double frame = SourceFrame(base, source, request, f);
    const int f0 = std::min(static_cast<int>(frame), source.num_frames - 2);
    const double alpha = frame - f0, weight = SourceWeight(base, request, f);
    for (int body : request.source_bodies) {
      const Quat from_source = source.local(f0, body).slerp(alpha, source.local(f0 + 1, body)).normalized();
      out.local(f, body) = weight < 1.0 ? base.local(f, body).slerp(weight, from_source).normalized() : from_source;
    }
  }
  if (auto status = ValidateClip(out); !status.ok()) return status;
  if (auto status = PlaceOnGround(spec, &out); !status.ok()) return status;
  return out;
}

}  // namespace modskill
