#include "server/core/motion/clip_view.h"

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace modskill {
namespace {

std::array<double, 3> Array(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

ViewerGeom GeomFromSpec(const GeomSpec& g) {
  ViewerGeom geom;
  switch (g.type) {
    case GeomSpec::Type::kSphere:
      geom.type = ViewerGeom::Type::kSphere;
      break;
    case GeomSpec::Type::kCapsule:
      geom.type = ViewerGeom::Type::kCapsule;
      break;
    case GeomSpec::Type::kBox:
      geom.type = ViewerGeom::Type::kBox;
      break;
  }
  geom.radius = g.radius;
  geom.half_extents = Array(g.half_extents);
  geom.from = Array(g.from);
  geom.to = Array(g.to);
  geom.center = Array(g.center);
  return geom;
}

}  // namespace

std::vector<ViewerBody> ViewerBodiesFromSpec(const HumanoidSpec& spec) {
  std::vector<ViewerBody> bodies;
  bodies.reserve(spec.num_bodies());
  for (const BodySpec& body : spec.bodies()) bodies.push_back({body.name, body.parent, GeomFromSpec(body.geom)});
  return bodies;
}

ViewerTrack ViewerTrackFromPoses(const std::vector<Vec3>& body_pos, const std::vector<Quat>& body_rot,
                                 ViewerTrack::Role role) {
  ViewerTrack track;
  track.role = role;
  track.pos.reserve(3 * body_pos.size());
  for (const Vec3& p : body_pos) track.pos.insert(track.pos.end(), {float(p.x()), float(p.y()), float(p.z())});
  track.rot.reserve(4 * body_rot.size());
  for (const Quat& q : body_rot) track.rot.insert(track.rot.end(), {float(q.w()), float(q.x()), float(q.y()), float(q.z())});
  return track;
}

absl::StatusOr<ViewerClip> ViewerClipFromMotion(const MotionClip& clip) {
  if (clip.num_frames <= 0) return absl::InvalidArgumentError(absl::StrFormat("clip '%s': zero frames", clip.name));
  const size_t poses = static_cast<size_t>(clip.num_frames) * clip.num_bodies;
  if (clip.body_pos.size() != poses || clip.body_rot.size() != poses) {
    return absl::FailedPreconditionError(
        absl::StrFormat("clip '%s': body poses not computed (%d of %d)", clip.name, clip.body_pos.size(), poses));
  }
  ViewerClip view;
  view.name = clip.name;
  view.label = clip.label;
  view.fps = clip.fps;
  view.num_frames = clip.num_frames;
  view.tracks.push_back(ViewerTrackFromPoses(clip.body_pos, clip.body_rot, ViewerTrack::Role::kReference));
  return view;
}

}  // namespace modskill
