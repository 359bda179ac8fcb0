#include "common/viewer/viewer_html.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>

#include <nlohmann/json.hpp>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_replace.h"
#include "common/atomic_file.h"
#include "common/viewer/viewer_page_html.h"  // generated: kViewerPageTemplate

namespace modskill {
namespace {

constexpr size_t kMaxThreeJsBytes = 16u << 20;

// Little-endian float32 bytes, base64: what the page turns into a Float32Array.
std::string Float32Base64(const std::vector<float>& values) {
  std::string bytes(values.size() * 4, '\0');
  for (size_t i = 0; i < values.size(); ++i) {
    uint32_t bits;
    std::memcpy(&bits, &values[i], 4);
    for (int b = 0; b < 4; ++b) bytes[4 * i + b] = static_cast<char>((bits >> (8 * b)) & 0xff);
  }
  return absl::Base64Escape(bytes);
}

std::string BytesBase64(const std::vector<uint8_t>& values) {
  return absl::Base64Escape(absl::string_view(reinterpret_cast<const char*>(values.data()), values.size()));
}

nlohmann::json Vec(const std::array<double, 3>& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }

nlohmann::json GeomJson(const ViewerGeom& g) {
  nlohmann::json json;
  switch (g.type) {
    case ViewerGeom::Type::kSphere:
      json = {{"type", "sphere"}, {"radius", g.radius}, {"center", Vec(g.center)}};
      break;
    case ViewerGeom::Type::kCapsule:
      json = {{"type", "capsule"}, {"radius", g.radius}, {"from", Vec(g.from)}, {"to", Vec(g.to)}};
      break;
    case ViewerGeom::Type::kBox:
      json = {{"type", "box"}, {"half_extents", Vec(g.half_extents)}, {"center", Vec(g.center)}};
      break;
  }
  return json;
}

nlohmann::json ClipJson(const ViewerClip& clip) {
  nlohmann::json tracks = nlohmann::json::array();
  for (const ViewerTrack& track : clip.tracks) {
    tracks.push_back({{"role", track.role == ViewerTrack::Role::kReference ? "reference" : "simulated"},
                      {"pos", Float32Base64(track.pos)},
                      {"rot", Float32Base64(track.rot)}});
  }
  nlohmann::json json = {{"name", clip.name}, {"label", clip.label}, {"fps", clip.fps},
                         {"frames", clip.num_frames}, {"tracks", tracks}};
  json["body_error"] = clip.body_error.empty() ? nlohmann::json() : nlohmann::json(Float32Base64(clip.body_error));
  json["flags"] = clip.flags.empty() ? nlohmann::json() : nlohmann::json(BytesBase64(clip.flags));
  return json;
}

bool AllFinite(const std::vector<float>& values) {
  for (float v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

absl::Status ValidateClip(const ViewerClip& clip, size_t index, size_t num_bodies) {
  const std::string where = absl::StrFormat("clip %d '%s'", index, clip.name);
  if (clip.num_frames <= 0) return absl::InvalidArgumentError(absl::StrCat(where, ": no frames"));
  if (!(std::isfinite(clip.fps) && clip.fps > 0)) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: fps %g is not positive", where, clip.fps));
  }
  if (clip.tracks.empty() || clip.tracks.size() > 2) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: %d tracks (expected 1 or 2)", where, clip.tracks.size()));
  }
  const size_t frames = static_cast<size_t>(clip.num_frames);
  for (const ViewerTrack& track : clip.tracks) {
    if (track.pos.size() != frames * num_bodies * 3 || track.rot.size() != frames * num_bodies * 4) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: track has %d positions and %d rotations, expected %d frames x %d bodies x 3 and x 4", where,
          track.pos.size(), track.rot.size(), frames, num_bodies));
    }
    if (!AllFinite(track.pos) || !AllFinite(track.rot)) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": a body pose is not finite"));
    }
  }
  if (!clip.body_error.empty() && clip.body_error.size() != frames) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: body_error has %d values for %d frames", where, clip.body_error.size(), frames));
  }
  if (!clip.flags.empty() && clip.flags.size() != frames) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: flags has %d values for %d frames", where, clip.flags.size(), frames));
  }
  return absl::OkStatus();
}

}  // namespace

std::string ThreeJsPath() {
  const char* env = std::getenv("MODSKILL_THREE_JS");
  return env != nullptr && env[0] != '\0' ? std::string(env) : std::string(kDefaultThreeJsPath);
}

absl::StatusOr<std::string> LoadThreeJs() {
  const std::string path = ThreeJsPath();
  absl::StatusOr<std::string> text = ReadFileToString(path, kMaxThreeJsBytes);
  if (!text.ok()) {
    return absl::FailedPreconditionError(absl::StrCat(
        "three.js for the HTML viewer: ", text.status().message(),
        " (install Debian's libjs-three, or set MODSKILL_THREE_JS to a three.min.js)"));
  }
  if (absl::StrContains(absl::AsciiStrToLower(*text), "</script")) {
    return absl::FailedPreconditionError(absl::StrCat(path, ": contains '</script', cannot be inlined"));
  }
  return text;
}

absl::Status ValidateViewerScene(const ViewerScene& scene) {
  if (scene.bodies.empty()) return absl::InvalidArgumentError("viewer scene: no bodies");
  if (scene.clips.empty()) return absl::InvalidArgumentError("viewer scene: no clips");
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    const int parent = scene.bodies[i].parent;
    if (parent >= static_cast<int>(i) || (i > 0 && parent < 0)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("viewer scene: body %d '%s' has parent %d", i, scene.bodies[i].name, parent));
    }
  }
  for (size_t c = 0; c < scene.clips.size(); ++c) {
    if (auto status = ValidateClip(scene.clips[c], c, scene.bodies.size()); !status.ok()) return status;
  }
  return absl::OkStatus();
}

std::string ViewerSceneJson(const ViewerScene& scene) {
  nlohmann::json bodies = nlohmann::json::array();
  for (const ViewerBody& body : scene.bodies) {
    bodies.push_back({{"name", body.name}, {"parent", body.parent}, {"geom", GeomJson(body.geom)}});
  }
  nlohmann::json clips = nlohmann::json::array();
  for (const ViewerClip& clip : scene.clips) clips.push_back(ClipJson(clip));
  const nlohmann::json json = {{"version", 1}, {"title", scene.title}, {"bodies", bodies}, {"clips", clips}};
  // Invalid UTF-8 in a name is replaced rather than thrown on.
  return json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

absl::StatusOr<std::string> RenderViewerHtml(const ViewerScene& scene, absl::string_view three_js) {
  if (auto status = ValidateViewerScene(scene); !status.ok()) return status;
  // '<' only occurs inside JSON strings: as \u003c it can neither close the script element
  // nor open a comment.
  const std::string json = absl::StrReplaceAll(ViewerSceneJson(scene), {{"<", "\\u003c"}});
  const std::string title = absl::StrReplaceAll(scene.title, {{"&", "&amp;"}, {"<", "&lt;"}, {">", "&gt;"}});
  return absl::StrReplaceAll(kViewerPageTemplate, {{"/*MODSKILL_THREE_JS*/", three_js},
                                                   {"MODSKILL_SCENE_JSON", json},
                                                   {"MODSKILL_PAGE_TITLE", title}});
}

absl::Status WriteViewerHtml(const std::string& path, const ViewerScene& scene) {
  if (auto status = ValidateViewerScene(scene); !status.ok()) return status;
  absl::StatusOr<std::string> three_js = LoadThreeJs();
  if (!three_js.ok()) return three_js.status();
  absl::StatusOr<std::string> html = RenderViewerHtml(scene, *three_js);
  if (!html.ok()) return html.status();
  return WriteFileAtomically(path, *html);
}

}  // namespace modskill
