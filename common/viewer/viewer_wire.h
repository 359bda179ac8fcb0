// The viewer's numbers (viewer_scene.h) to and from the wire: the character's collision
// geometry (EnvSpec.body_geometry, filled by the server) and a rollout's streamed frames
// (RolloutFrame), so that every client (the CLI, the learner's evaluation, Python) draws exactly
// what the server simulated.
#ifndef MODSKILL_COMMON_VIEWER_VIEWER_WIRE_H_
#define MODSKILL_COMMON_VIEWER_VIEWER_WIRE_H_

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/viewer/viewer_scene.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

void ToWire(const ViewerBody& body, v1::BodyGeometry* out);

// One body per EnvSpec.body_names entry, with its geometry; an error names the body and field
// (a server without geometry, e.g. one older than the viewer, is FAILED_PRECONDITION).
absl::StatusOr<std::vector<ViewerBody>> ViewerBodiesFromWire(const v1::EnvSpec& spec);

// Collects streamed RolloutFrames into a viewer scene: per clip, in the order the clips first
// appear, the reference and the simulated track, the mean body error and done/terminated flags.
class RolloutViewerRecorder {
 public:
  // Geometry (ViewerBodiesFromWire) and frame rate (1 / control_dt) from the server's spec, so
  // that a server without geometry fails before the rollout runs.
  static absl::StatusOr<RolloutViewerRecorder> ForSpec(const v1::EnvSpec& spec);

  // A motor-skill family's rollout at other body proportions (ClipMetrics.family.params'
  // leg_scale and arm_scale): the limbs are drawn stretched as the server stretched them
  // (FamilyLimbScale), not at the session's default geometry.
  void ScaleFamilyLimbs(double leg_scale, double arm_scale);

  // Captions by clip name (ListMotions' labels), shown under the clip's name.
  void set_labels(std::map<std::string, std::string> labels) { labels_ = std::move(labels); }

  // Records one frame. The first malformed frame (DATA_LOSS naming the field) is kept as error()
  // and every later frame is ignored.
  void Add(const v1::RolloutFrame& frame);
  const absl::Status& error() const { return error_; }
  int64_t num_frames() const { return num_frames_; }

  // The recorded clips as a scene (moved out); fails with error(), or when no frame came.
  absl::StatusOr<ViewerScene> TakeScene(std::string title);

 private:
  RolloutViewerRecorder(std::vector<ViewerBody> bodies, double fps) : bodies_(std::move(bodies)), fps_(fps) {}
  absl::Status Record(const v1::RolloutFrame& frame);
  ViewerClip& ClipNamed(const std::string& name);

  std::vector<ViewerBody> bodies_;
  double fps_;
  std::map<std::string, std::string> labels_;
  std::map<std::string, size_t> index_of_;
  std::vector<ViewerClip> clips_;
  absl::Status error_;
  int64_t num_frames_ = 0;
};

// Writes the recorder's scene as a page at `path` (WriteViewerHtml: atomic, no partial file);
// returns the number of clips written.
absl::StatusOr<size_t> WriteRolloutPage(RolloutViewerRecorder& recorder, std::string title, const std::string& path);

// A recorder for a page of a server's rollout: geometry and frame rate from `spec`, captions from
// `motions`, and three.js found now (LoadThreeJs) rather than after minutes of rollout.
absl::StatusOr<RolloutViewerRecorder> PrepareRolloutPage(const v1::EnvSpec& spec,
                                                         const v1::ListMotionsResponse& motions);

}  // namespace modskill

#endif  // MODSKILL_COMMON_VIEWER_VIEWER_WIRE_H_
