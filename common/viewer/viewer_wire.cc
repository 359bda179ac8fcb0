#include "common/viewer/viewer_wire.h"

#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/policy/family_parameters.h"
#include "common/shown_value.h"
#include "common/viewer/viewer_html.h"
#include "common/wire/tensor_codec.h"

namespace modskill {
namespace {

void SetVec(const std::array<double, 3>& v, google::protobuf::RepeatedField<float>* out) {
  out->Clear();
  for (double x : v) out->Add(static_cast<float>(x));
}

// A 3-vector field: empty reads as zero (a sphere has no segment), else exactly 3 finite values.
absl::Status ReadVec(const google::protobuf::RepeatedField<float>& values, const std::string& field,
                     std::array<double, 3>* out) {
  *out = {0, 0, 0};
  if (values.empty()) return absl::OkStatus();
  if (values.size() != 3) {
    return absl::DataLossError(absl::StrFormat("%s: %d values (expected 3)", field, values.size()));
  }
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(values[k])) return absl::DataLossError(absl::StrCat(field, ": not finite"));
    (*out)[k] = values[k];
  }
  return absl::OkStatus();
}

absl::StatusOr<ViewerGeom> GeomFromWire(const v1::BodyGeometry& wire, const std::string& where) {
  ViewerGeom geom;
  switch (wire.shape()) {
    case v1::BodyGeometry::SPHERE: geom.type = ViewerGeom::Type::kSphere; break;
    case v1::BodyGeometry::CAPSULE: geom.type = ViewerGeom::Type::kCapsule; break;
    case v1::BodyGeometry::BOX: geom.type = ViewerGeom::Type::kBox; break;
    default:
      return absl::DataLossError(absl::StrCat(where, ".shape: unknown shape ", static_cast<int>(wire.shape())));
  }
  if (!std::isfinite(wire.radius()) || wire.radius() < 0) {
    return absl::DataLossError(absl::StrCat(where, ".radius: not a finite non-negative length"));
  }
  geom.radius = wire.radius();
  for (auto [values, name, out] : {std::tuple{&wire.half_extents(), "half_extents", &geom.half_extents},
                                   std::tuple{&wire.segment_from(), "segment_from", &geom.from},
                                   std::tuple{&wire.segment_to(), "segment_to", &geom.to},
                                   std::tuple{&wire.center(), "center", &geom.center}}) {
    if (absl::Status status = ReadVec(*values, absl::StrCat(where, ".", name), out); !status.ok()) return status;
  }
  return geom;
}

}  // namespace

void ToWire(const ViewerBody& body, v1::BodyGeometry* out) {
  out->set_parent(body.parent);
  switch (body.geom.type) {
    case ViewerGeom::Type::kSphere: out->set_shape(v1::BodyGeometry::SPHERE); break;
    case ViewerGeom::Type::kCapsule: out->set_shape(v1::BodyGeometry::CAPSULE); break;
    case ViewerGeom::Type::kBox: out->set_shape(v1::BodyGeometry::BOX); break;
  }
  out->set_radius(static_cast<float>(body.geom.radius));
  SetVec(body.geom.half_extents, out->mutable_half_extents());
  SetVec(body.geom.from, out->mutable_segment_from());
  SetVec(body.geom.to, out->mutable_segment_to());
  SetVec(body.geom.center, out->mutable_center());
}

absl::StatusOr<std::vector<ViewerBody>> ViewerBodiesFromWire(const v1::EnvSpec& spec) {
  if (spec.body_geometry_size() == 0) {
    return absl::FailedPreconditionError("EnvSpec.body_geometry: the server sent no geometry (a server older than the viewer?)");
  }
  if (spec.body_geometry_size() != spec.body_names_size()) {
    return absl::DataLossError(absl::StrFormat("EnvSpec.body_geometry: %d entries for %d body_names",
                                               spec.body_geometry_size(), spec.body_names_size()));
  }
  std::vector<ViewerBody> bodies;
  for (int b = 0; b < spec.body_geometry_size(); ++b) {
    const v1::BodyGeometry& wire = spec.body_geometry(b);
    const std::string where = absl::StrFormat("EnvSpec.body_geometry[%d] (%s)", b, ShownValue(spec.body_names(b)));
    if (wire.parent() >= b || wire.parent() < (b == 0 ? -1 : 0)) {
      return absl::DataLossError(absl::StrFormat("%s.parent: %d is not an earlier body", where, wire.parent()));
    }
    absl::StatusOr<ViewerGeom> geom = GeomFromWire(wire, where);
    if (!geom.ok()) return geom.status();
    bodies.push_back({spec.body_names(b), wire.parent(), *geom});
  }
  return bodies;
}

absl::StatusOr<RolloutViewerRecorder> RolloutViewerRecorder::ForSpec(const v1::EnvSpec& spec) {
  absl::StatusOr<std::vector<ViewerBody>> bodies = ViewerBodiesFromWire(spec);
  if (!bodies.ok()) return bodies.status();
  if (!(std::isfinite(spec.control_dt()) && spec.control_dt() > 0)) {
    return absl::DataLossError(absl::StrCat("EnvSpec.control_dt: ", spec.control_dt(), " is not a positive time"));
  }
  return RolloutViewerRecorder(*std::move(bodies), 1.0 / spec.control_dt());
}

ViewerClip& RolloutViewerRecorder::ClipNamed(const std::string& name) {
  auto [it, inserted] = index_of_.emplace(name, clips_.size());
  if (inserted) {
    ViewerClip clip;
    clip.name = name;
    if (auto label = labels_.find(name); label != labels_.end()) clip.label = label->second;
    clip.fps = fps_;
    clip.tracks.resize(2);
    clip.tracks[0].role = ViewerTrack::Role::kReference;
    clip.tracks[1].role = ViewerTrack::Role::kSimulated;
    clips_.push_back(std::move(clip));
  }
  return clips_[it->second];
}

void RolloutViewerRecorder::Add(const v1::RolloutFrame& frame) {
  if (error_.ok()) error_ = Record(frame);
}

absl::Status RolloutViewerRecorder::Record(const v1::RolloutFrame& frame) {
  const int64_t n = static_cast<int64_t>(bodies_.size());
  // Read all four first so that a bad frame leaves the clip as it was.
  std::vector<float> poses[4];
  const std::pair<const v1::Tensor*, const char*> fields[4] = {
      {&frame.ref_body_pos(), "RolloutFrame.ref_body_pos"}, {&frame.ref_body_rot(), "RolloutFrame.ref_body_rot"},
      {&frame.sim_body_pos(), "RolloutFrame.sim_body_pos"}, {&frame.sim_body_rot(), "RolloutFrame.sim_body_rot"}};
  for (int k = 0; k < 4; ++k) {
    const int64_t width = k % 2 == 0 ? 3 : 4;
    if (absl::Status status = ReadFloatTensor(*fields[k].first, fields[k].second, {n, width}, &poses[k]);
        !status.ok()) {
      return AsDataLoss(status);
    }
  }
  if (!std::isfinite(frame.mean_body_error_m())) {
    return absl::DataLossError("RolloutFrame.mean_body_error_m: not finite");
  }
  ViewerClip& clip = ClipNamed(frame.clip());
  for (int k = 0; k < 4; ++k) {
    std::vector<float>& track = k % 2 == 0 ? clip.tracks[k / 2].pos : clip.tracks[k / 2].rot;
    track.insert(track.end(), poses[k].begin(), poses[k].end());
  }
  clip.body_error.push_back(frame.mean_body_error_m());
  clip.flags.push_back(static_cast<uint8_t>((frame.done() ? kViewerDone : 0) |
                                            (frame.terminated() ? kViewerTerminated : 0) |
                                            (frame.done() && !frame.terminated() ? kViewerTruncated : 0)));
  ++clip.num_frames;
  ++num_frames_;
  return absl::OkStatus();
}

absl::StatusOr<ViewerScene> RolloutViewerRecorder::TakeScene(std::string title) {
  if (!error_.ok()) return error_;
  if (clips_.empty()) return absl::FailedPreconditionError("rollout: no frames were streamed, nothing to show");
  ViewerScene scene;
  scene.title = std::move(title);
  scene.bodies = bodies_;
  scene.clips = std::move(clips_);
  clips_.clear();
  index_of_.clear();
  return scene;
}

absl::StatusOr<size_t> WriteRolloutPage(RolloutViewerRecorder& recorder, std::string title, const std::string& path) {
  absl::StatusOr<ViewerScene> scene = recorder.TakeScene(std::move(title));
  if (!scene.ok()) return scene.status();
  if (absl::Status status = WriteViewerHtml(path, *scene); !status.ok()) return status;
  return scene->clips.size();
}

absl::StatusOr<RolloutViewerRecorder> PrepareRolloutPage(const v1::EnvSpec& spec,
                                                         const v1::ListMotionsResponse& motions) {
  if (absl::StatusOr<std::string> three_js = LoadThreeJs(); !three_js.ok()) return three_js.status();
  absl::StatusOr<RolloutViewerRecorder> recorder = RolloutViewerRecorder::ForSpec(spec);
  if (!recorder.ok()) return recorder.status();
  std::map<std::string, std::string> labels;
  for (const v1::MotionInfo& motion : motions.motions()) labels[motion.name()] = motion.label();
  recorder->set_labels(std::move(labels));
  return recorder;
}

void RolloutViewerRecorder::ScaleFamilyLimbs(double leg_scale, double arm_scale) {
  for (ViewerBody& body : bodies_) {
    const double scale = FamilyLimbScale(body.name, leg_scale, arm_scale);
    ViewerGeom& g = body.geom;
    g.radius *= scale;
    for (int k = 0; k < 3; ++k) {
      g.half_extents[k] *= scale;
      g.from[k] *= scale;
      g.to[k] *= scale;
      g.center[k] *= scale;
    }
  }
}

}  // namespace modskill
