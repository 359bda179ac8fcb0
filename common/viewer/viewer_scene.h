// What an HTML viewer page shows, as plain numbers: the character's collision geometry (one
// geom per body, in the body's frame) and, per clip, one or two tracks of world body poses
// (the reference, and the simulated character when there is one) plus per-frame text. Free of
// physics and gRPC so that the server, the client and the learner can all fill it.
#ifndef MODSKILL_COMMON_VIEWER_VIEWER_SCENE_H_
#define MODSKILL_COMMON_VIEWER_VIEWER_SCENE_H_

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace modskill {

struct ViewerGeom {
  enum class Type { kSphere, kCapsule, kBox };
  Type type = Type::kSphere;
  double radius = 0;                           // sphere and capsule
  std::array<double, 3> half_extents{};        // box, axis-aligned in the body frame
  std::array<double, 3> from{}, to{};          // capsule segment, body frame
  std::array<double, 3> center{};              // sphere and box, body frame
};

struct ViewerBody {
  std::string name;
  int parent = -1;
  ViewerGeom geom;
};

// World poses of every body in every frame: pos [frame * num_bodies + body][xyz] and rot
// [frame * num_bodies + body][wxyz] (MuJoCo's quaternion order), z up.
struct ViewerTrack {
  enum class Role { kReference, kSimulated };
  Role role = Role::kReference;
  std::vector<float> pos;  // num_frames * num_bodies * 3
  std::vector<float> rot;  // num_frames * num_bodies * 4
};

// Per-frame flags of a simulated track.
enum ViewerFrameFlag : uint8_t { kViewerDone = 1, kViewerTerminated = 2, kViewerTruncated = 4 };

struct ViewerClip {
  std::string name;
  std::string label;  // caption, may be empty
  double fps = 30;
  int num_frames = 0;
  std::vector<ViewerTrack> tracks;  // one or two (reference and simulated)
  std::vector<float> body_error;    // mean body position error per frame (m), empty when none
  std::vector<uint8_t> flags;       // ViewerFrameFlag bits per frame, empty when none
};

struct ViewerScene {
  std::string title;
  std::vector<ViewerBody> bodies;
  std::vector<ViewerClip> clips;
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_VIEWER_VIEWER_SCENE_H_
