// One self-contained HTML page per view: the page template (embedded at build time), three.js
// (Debian's libjs-three, read at run time and inlined) and the scene as JSON, with float
// arrays as base64 little-endian float32. The page works offline, opened from disk.
#ifndef MODSKILL_COMMON_VIEWER_VIEWER_HTML_H_
#define MODSKILL_COMMON_VIEWER_VIEWER_HTML_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/viewer/viewer_scene.h"

namespace modskill {

// Where three.js is read from: $MODSKILL_THREE_JS when set, else this (Debian's libjs-three).
inline constexpr char kDefaultThreeJsPath[] = "/usr/share/javascript/three/three.min.js";
std::string ThreeJsPath();

// Reads ThreeJsPath(); the error names the path and the package to install.
absl::StatusOr<std::string> LoadThreeJs();

// Sizes consistent (tracks, error and flags per frame), at least one clip and one frame per
// clip, finite numbers; the message names the clip and field.
absl::Status ValidateViewerScene(const ViewerScene& scene);

// The scene as the page's JSON (what the page's script reads as MODSKILL_SCENE).
std::string ViewerSceneJson(const ViewerScene& scene);

// The page: template + three.js + scene JSON. Validates the scene first.
absl::StatusOr<std::string> RenderViewerHtml(const ViewerScene& scene, absl::string_view three_js);

// Renders with LoadThreeJs() and writes `path` atomically (no partial file on any error).
absl::Status WriteViewerHtml(const std::string& path, const ViewerScene& scene);

}  // namespace modskill

#endif  // MODSKILL_COMMON_VIEWER_VIEWER_HTML_H_
