// modskill-motion: imports motion files into the native clip format, inspects clips, writes
// them as one self-contained HTML page, splices one clip's parts onto another, and makes held
// reach poses, and bends a clip's path into a turn.
//
//   modskill-motion import IN... --out DIR [--labels CSV] [--fps 30]
//   modskill-motion inspect FILE...
//   modskill-motion view CLIP... --html OUT.html   (CLIP: a motion file or a library clip name)
//   modskill-motion splice BASE SOURCE --parts R_Arm,L_Arm --name NAME --out DIR
//   modskill-motion reach BASE --count 32 --name NAME --out DIR   (held reach poses by IK)
//   modskill-motion turn BASE --yaw_rate 45 --name NAME --out DIR   (the path bent at 45 deg/s)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/task_settings.h"
#include "common/viewer/viewer_html.h"
#include "server/core/motion/clip_file.h"
#include "server/core/motion/clip_view.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/stance_feet.h"
#include "server/core/motion/motion_library.h"
#include "server/core/motion/motion_splice.h"
#include "server/core/motion/motion_turn.h"
#include "server/core/motion/reach_pose.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/core/util/confined_path.h"

ABSL_FLAG(std::string, out, "", "import, splice, reach, turn: directory the .msclip files are written to");
ABSL_FLAG(std::string, labels, "", "import: CSV 'name,humanml3d_id,label' giving clips their captions");
ABSL_FLAG(double, fps, 30.0, "import, inspect, view: rate the clips are resampled to (the control rate)");
ABSL_FLAG(bool, ground, true, "import, inspect, view: shift each clip so that its lowest point touches the floor");
ABSL_FLAG(std::string, floor, "window",
          "import, inspect, view: the floor a clip is put on: 'window' (a low quantile of the lowest points within "
          "0.5 s) or 'stance' (that floor pinned to the supporting foot wherever one carries the body)");
ABSL_FLAG(std::string, html, "", "view: the HTML page written (written atomically: no partial file)");
ABSL_FLAG(std::vector<std::string>, parts, {}, "splice: the parts (of --layout) whose motion comes from SOURCE");
ABSL_FLAG(std::string, layout, "", "splice: the part layout naming --parts (default: data/part_layouts.json's)");
ABSL_FLAG(std::string, timing, "stretch",
          "splice: stretch (SOURCE's whole duration over BASE's), clip (SOURCE at its own speed, held at its end) or "
          "hold (SOURCE's pose at --hold_at held throughout, reached from BASE's pose over the first second)");
ABSL_FLAG(double, hold_at, 0.5, "splice --timing hold: the held pose's time, a share of SOURCE's duration in [0, 1]");
ABSL_FLAG(std::string, name, "", "splice, turn: the new clip's name (its file is DIR/NAME.msclip); reach: the prefix of NAME_000...");
ABSL_FLAG(double, yaw_rate, 0.0, "turn: the path's yaw rate in deg/s, positive to the left (|rate| <= 180)");
ABSL_FLAG(std::string, hand, "R_Hand", "reach: the body brought to each target; its part's chain up to it moves");
ABSL_FLAG(int, count, 32, "reach: how many clips, one per target drawn uniformly in the box");
ABSL_FLAG(int, seed, 1, "reach: the seed of the targets");
ABSL_FLAG(double, box_size, 2.0, "reach: the target box's edge (m), as the reach task's --task_reach_box_size");
ABSL_FLAG(std::vector<std::string>, box_center, std::vector<std::string>({"0", "0", "1"}),
          "reach: the box's centre x,y,z (m) in the heading frame on the ground, as the reach task's");

namespace modskill {
namespace {

struct ClipLabel {
  std::string humanml3d_id;
  std::string label;
};

// name,humanml3d_id,label (label may contain commas); '#' starts a comment line.
bool ReadLabels(const std::string& path, std::map<std::string, ClipLabel>* labels) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "error: --labels %s: cannot open\n", path.c_str());
    return false;
  }
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields = absl::StrSplit(line, absl::MaxSplits(',', 2));
    if (fields.size() != 3) {
      std::fprintf(stderr, "error: --labels %s:%d: expected name,humanml3d_id,label\n", path.c_str(), line_number);
      return false;
    }
    (*labels)[fields[0]] = ClipLabel{std::string(absl::StripAsciiWhitespace(fields[1])),
                                     std::string(absl::StripAsciiWhitespace(fields[2]))};
  }
  return true;
}

// --fps, --ground and --floor as import options.
absl::StatusOr<ImportOptions> ImportOptionsFromFlags() {
  ImportOptions options;
  options.target_fps = absl::GetFlag(FLAGS_fps);
  options.place_on_ground = absl::GetFlag(FLAGS_ground);
  const std::string floor = absl::GetFlag(FLAGS_floor);
  if (floor == "stance") {
    options.floor = FloorMode::kStance;
  } else if (floor != "window") {
    return absl::InvalidArgumentError(absl::StrFormat("--floor '%s': expected window or stance", floor));
  }
  return options;
}

void PrintSummary(const HumanoidSpec& spec, const MotionClip& clip, const std::string& file) {
  double min_height = 1e9, max_height = -1e9, mean_height = 0;
  for (int f = 0; f < clip.num_frames; ++f) {
    const double z = clip.body_pos[f * clip.num_bodies].z();
    min_height = std::min(min_height, z);
    max_height = std::max(max_height, z);
    mean_height += z / clip.num_frames;
  }
  // Standing height: from the lowest geometry point to the top of the head in the first frame.
  const int head = spec.BodyIndex("Head");
  double top = 0;
  if (head >= 0) top = clip.body_pos[head].z() + spec.body(head).geom.radius;
  std::printf("%s\n", file.c_str());
  std::printf("  name            %s\n", clip.name.c_str());
  std::printf("  label           %s\n", clip.label.empty() ? "-" : clip.label.c_str());
  std::printf("  humanml3d_id    %s\n", clip.humanml3d_id.empty() ? "-" : clip.humanml3d_id.c_str());
  std::printf("  source          %s\n", clip.source.c_str());
  std::printf("  frames          %d\n", clip.num_frames);
  std::printf("  fps             %.2f\n", clip.fps);
  std::printf("  duration        %.3f s\n", clip.duration());
  std::printf("  height          %.3f m (head top above the floor, frame 0)\n", top - LowestGeomPoint(spec, clip, 0));
  std::printf("  root height     mean %.3f  min %.3f  max %.3f m\n", mean_height, min_height, max_height);
  std::printf("  foot contact    %.1f %% of frames\n", 100.0 * FootContactRatio(spec, clip));
  // How far each frame's lowest geometry point is above the floor: a walk or a crawl should
  // stay near 0 (a retargeted clip that floats cannot be tracked); a flight rises.
  double clearance_sum = 0, clearance_max = 0;
  for (int f = 0; f < clip.num_frames; ++f) {
    const double clearance = LowestGeomPoint(spec, clip, f);
    clearance_sum += clearance;
    clearance_max = std::max(clearance_max, clearance);
  }
  std::printf("  floor clearance mean %.3f  max %.3f m (lowest point per frame)\n",
              clearance_sum / std::max(1, clip.num_frames), clearance_max);
  // A foot that carries the body should be flat on the floor: a tilt here is the retargeting's.
  const StanceFeet stance = MeasureStanceFeet(spec, clip);
  std::printf("  stance feet     pitch %+.1f deg (toe up > 0)  clearance %.3f m  over %d foot-frames\n",
              stance.mean_pitch_deg, stance.mean_clearance, stance.stance_samples);
}

int Import(const std::vector<std::string>& inputs, const HumanoidSpec& spec, const ImportOptions& options) {
  const std::string out_dir = absl::GetFlag(FLAGS_out);
  if (out_dir.empty()) {
    std::fprintf(stderr, "error: import needs --out DIR\n");
    return 2;
  }
  std::map<std::string, ClipLabel> labels;
  if (!absl::GetFlag(FLAGS_labels).empty() && !ReadLabels(absl::GetFlag(FLAGS_labels), &labels)) return 2;
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  if (error) {
    std::fprintf(stderr, "error: --out %s: %s\n", out_dir.c_str(), error.message().c_str());
    return 2;
  }
  int failures = 0;
  for (const std::string& input : inputs) {
    ImportOptions file_options = options;
    auto label = labels.find(DefaultClipName(input));
    if (label != labels.end()) {
      file_options.label = label->second.label;
      file_options.humanml3d_id = label->second.humanml3d_id;
    }
    auto clip = ImportMotionFile(input, spec, file_options);
    if (!clip.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(clip.status().message()).c_str());
      ++failures;
      continue;
    }
    // The importer checked the name; the path is confined to --out all the same.
    auto confined = ConfinedPath(out_dir, clip->name + std::string(kClipFileExtension));
    if (!confined.ok()) {
      std::fprintf(stderr, "error: %s: %s\n", input.c_str(), std::string(confined.status().message()).c_str());
      ++failures;
      continue;
    }
    const std::string& out_path = *confined;
    if (auto status = WriteClipFile(out_path, *clip); !status.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
      ++failures;
      continue;
    }
    std::printf("%-28s %5d frames  %6.2f s  contact %5.1f%%  -> %s\n", clip->name.c_str(), clip->num_frames,
                clip->duration(), 100.0 * FootContactRatio(spec, *clip), out_path.c_str());
  }
  return failures == 0 ? 0 : 1;
}

int Inspect(const std::vector<std::string>& files, const HumanoidSpec& spec, const ImportOptions& options) {
  int failures = 0;
  for (const std::string& file : files) {
    auto clip = ImportMotionFile(file, spec, options);
    if (!clip.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(clip.status().message()).c_str());
      ++failures;
      continue;
    }
    PrintSummary(spec, *clip, file);
  }
  return failures == 0 ? 0 : 1;
}

// A motion file (imported with `options`) when `input` names one, else the clip of that name in
// the default library (loaded on first need into `library`).
absl::StatusOr<MotionClip> ResolveClip(const std::string& input, const HumanoidSpec& spec,
                                       const ImportOptions& options, std::optional<MotionLibrary>* library) {
  std::error_code error;
  if (std::filesystem::exists(input, error)) return ImportMotionFile(input, spec, options);
  if (!library->has_value()) {
    absl::StatusOr<MotionLibrary> loaded = MotionLibrary::LoadDefault(spec);
    if (!loaded.ok()) {
      return absl::NotFoundError(absl::StrFormat("clip '%s': no such file, and the default library did not load: %s",
                                                 input, loaded.status().message()));
    }
    library->emplace(*std::move(loaded));
  }
  const int id = (*library)->Find(input);
  if (id < 0) {
    return absl::NotFoundError(absl::StrFormat(
        "clip '%s': no such file, and no clip of that name in the default library (%d clips; "
        "modskill-motion inspect lists a file's name)",
        input, (*library)->size()));
  }
  return (*library)->clip(id);
}

// Every clip must resolve before anything is written: a bad name leaves no page behind.
int View(const std::vector<std::string>& inputs, const HumanoidSpec& spec, const ImportOptions& options) {
  const std::string out = absl::GetFlag(FLAGS_html);
  if (out.empty()) {
    std::fprintf(stderr, "error: view needs --html OUT.html\n");
    return 2;
  }
  ViewerScene scene;
  scene.title = inputs.size() == 1 ? "modskill: " + inputs[0] : absl::StrFormat("modskill: %d clips", inputs.size());
  scene.bodies = ViewerBodiesFromSpec(spec);
  std::optional<MotionLibrary> library;
  for (const std::string& input : inputs) {
    absl::StatusOr<MotionClip> clip = ResolveClip(input, spec, options, &library);
    absl::StatusOr<ViewerClip> view = clip.ok() ? ViewerClipFromMotion(*clip) : clip.status();
    if (!view.ok()) {
      std::fprintf(stderr, "error: %s (nothing written to %s)\n", std::string(view.status().message()).c_str(),
                   out.c_str());
      return 1;
    }
    scene.clips.push_back(*std::move(view));
  }
  if (auto status = WriteViewerHtml(out, scene); !status.ok()) {
    std::fprintf(stderr, "error: --html %s\n", std::string(status.message()).c_str());
    return 1;
  }
  std::error_code error;
  const auto bytes = std::filesystem::file_size(out, error);
  std::printf("%s: %zu clip(s), %.1f MB\n", out.c_str(), scene.clips.size(), error ? 0.0 : bytes / 1e6);
  return 0;
}

// --layout, or the catalog's default.
absl::StatusOr<PartLayout> LayoutFromFlags(const HumanoidSpec& spec) {
  absl::StatusOr<PartLayoutCatalog> catalog = PartLayoutCatalog::LoadDefault(spec);
  if (!catalog.ok()) return catalog.status();
  const std::string layout_name = absl::GetFlag(FLAGS_layout).empty() ? catalog->default_name()
                                                                      : absl::GetFlag(FLAGS_layout);
  absl::StatusOr<PartLayout> layout = catalog->Get(layout_name);
  if (!layout.ok()) return absl::InvalidArgumentError(absl::StrCat("--layout: ", layout.status().message()));
  return layout;
}

// The bodies of the named parts of --layout, or an error naming the unknown part.
absl::StatusOr<std::vector<int>> PartBodies(const HumanoidSpec& spec) {
  absl::StatusOr<PartLayout> layout = LayoutFromFlags(spec);
  if (!layout.ok()) return layout.status();
  absl::StatusOr<std::vector<int>> bodies = layout->BodiesOfParts(absl::GetFlag(FLAGS_parts), "--parts");
  if (!bodies.ok()) return bodies.status();
  if (bodies->empty()) return absl::InvalidArgumentError("--parts: name at least one part");
  return bodies;
}

// --hand, and the bodies of its part on the way from the part's top down to it: the chain the
// inverse kinematics turns (R_Thorax, R_Shoulder, R_Elbow, R_Wrist, R_Hand in the 5-part layout).
absl::StatusOr<ReachPoseRequest> ReachChainFromFlags(const HumanoidSpec& spec) {
  ReachPoseRequest request;
  request.hand = spec.BodyIndex(absl::GetFlag(FLAGS_hand));
  if (request.hand <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("--hand '", absl::GetFlag(FLAGS_hand), "' is not a non-root body of the skeleton"));
  }
  absl::StatusOr<PartLayout> layout = LayoutFromFlags(spec);
  if (!layout.ok()) return layout.status();
  for (const BodyPart& part : layout->parts) {
    if (std::find(part.bodies.begin(), part.bodies.end(), request.hand) == part.bodies.end()) continue;
    for (int b = request.hand; b > 0; b = spec.body(b).parent) {
      if (std::find(part.bodies.begin(), part.bodies.end(), b) != part.bodies.end()) request.moved_bodies.push_back(b);
    }
  }
  return request;
}

// --box_size and --box_center, checked by the reach task's own bounds (TaskSettings::Validate), so
// the tool makes poses only for boxes a reach session accepts.
absl::StatusOr<std::pair<double, Vec3>> ReachBoxFromFlags() {
  const std::vector<std::string> center_text = absl::GetFlag(FLAGS_box_center);
  if (center_text.size() != 3) return absl::InvalidArgumentError("--box_center: expected x,y,z");
  TaskSettings box;
  box.reach_box_size = absl::GetFlag(FLAGS_box_size);
  for (int k = 0; k < 3; ++k) {
    if (!absl::SimpleAtod(center_text[k], &box.reach_center[k])) {
      return absl::InvalidArgumentError(absl::StrCat("--box_center '", center_text[k], "': not a number"));
    }
  }
  const absl::Status valid = box.Validate([](absl::string_view field) {
    return field == "reach_box_size" ? std::string("--box_size") : absl::StrCat("--box_center ", field.substr(13));
  });
  if (!valid.ok()) return valid;
  return std::make_pair(box.reach_box_size, Vec3(box.reach_center[0], box.reach_center[1], box.reach_center[2]));
}

// Writes one held reach pose per target drawn in the box, and prints how close each hand came.
int Reach(const std::vector<std::string>& inputs, const HumanoidSpec& spec, const ImportOptions& options) {
  const std::string out_dir = absl::GetFlag(FLAGS_out), prefix = absl::GetFlag(FLAGS_name);
  if (inputs.size() != 1 || out_dir.empty() || prefix.empty()) {
    std::fprintf(stderr, "error: reach needs BASE --name NAME --out DIR\n");
    return 2;
  }
  std::optional<MotionLibrary> library;
  absl::StatusOr<MotionClip> base = ResolveClip(inputs[0], spec, options, &library);
  absl::StatusOr<ReachPoseRequest> request = ReachChainFromFlags(spec);
  absl::StatusOr<std::pair<double, Vec3>> box = ReachBoxFromFlags();
  const int count = absl::GetFlag(FLAGS_count);
  const absl::Status count_ok = count >= 1 && count <= 1000
                                    ? absl::OkStatus()
                                    : absl::InvalidArgumentError(absl::StrCat("--count ", count, ": expected 1 to 1000"));
  for (const absl::Status& status : {base.status(), request.status(), box.status(), count_ok}) {
    if (!status.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
      return 2;
    }
  }
  std::mt19937_64 rng(absl::GetFlag(FLAGS_seed));
  std::uniform_real_distribution<double> unit(-0.5 * box->first, 0.5 * box->first);
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  std::vector<double> distances;
  for (int i = 0; i < count; ++i) {
    request->name = absl::StrFormat("%s_%03d", prefix, i);
    request->target = box->second + Vec3(unit(rng), unit(rng), unit(rng));
    absl::StatusOr<ReachPose> pose = MakeReachPose(spec, *base, *request);
    absl::StatusOr<std::string> path =
        pose.ok() ? ConfinedPath(out_dir, request->name + std::string(kClipFileExtension)) : pose.status();
    const absl::Status written = path.ok() ? WriteClipFile(*path, pose->clip) : path.status();
    if (!written.ok()) {
      std::fprintf(stderr, "error: %s: %s\n", request->name.c_str(), std::string(written.message()).c_str());
      return 1;
    }
    distances.push_back(pose->distance);
    std::printf("%-24s target (%+.2f, %+.2f, %.2f) m  hand %.3f m from it  -> %s\n", request->name.c_str(),
                request->target.x(), request->target.y(), request->target.z(), pose->distance, path->c_str());
  }
  std::sort(distances.begin(), distances.end());
  const auto within = std::count_if(distances.begin(), distances.end(), [](double d) { return d < 0.05; });
  std::printf("%zu clips: hand-to-target median %.3f m, %ld within 5 cm (the rest out of the arm's reach)\n",
              distances.size(), distances[distances.size() / 2], static_cast<long>(within));
  return 0;
}

// Writes a clip a tool made to DIR/NAME.msclip and prints one line about it.
int WriteMadeClip(const HumanoidSpec& spec, const std::string& out_dir, const MotionClip& clip) {
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  absl::StatusOr<std::string> path = ConfinedPath(out_dir, clip.name + std::string(kClipFileExtension));
  absl::Status written = path.ok() ? WriteClipFile(*path, clip) : path.status();
  if (!written.ok()) {
    std::fprintf(stderr, "error: --out %s: %s\n", out_dir.c_str(), std::string(written.message()).c_str());
    return 1;
  }
  std::printf("%-28s %5d frames  %6.2f s  contact %5.1f%%  -> %s\n", clip.name.c_str(), clip.num_frames,
              clip.duration(), 100.0 * FootContactRatio(spec, clip), path->c_str());
  return 0;
}

int Splice(const std::vector<std::string>& inputs, const HumanoidSpec& spec, const ImportOptions& options) {
  const std::string out_dir = absl::GetFlag(FLAGS_out);
  if (inputs.size() != 2 || out_dir.empty() || absl::GetFlag(FLAGS_name).empty()) {
    std::fprintf(stderr, "error: splice needs BASE SOURCE --parts P,... --name NAME --out DIR\n");
    return 2;
  }
  SpliceRequest request;
  request.name = absl::GetFlag(FLAGS_name);
  absl::StatusOr<SpliceTiming> timing = ParseSpliceTiming(absl::GetFlag(FLAGS_timing));
  absl::StatusOr<std::vector<int>> bodies = PartBodies(spec);
  std::optional<MotionLibrary> library;
  absl::StatusOr<MotionClip> base = ResolveClip(inputs[0], spec, options, &library);
  absl::StatusOr<MotionClip> source = ResolveClip(inputs[1], spec, options, &library);
  for (const absl::Status& status : {timing.status(), bodies.status(), base.status(), source.status()}) {
    if (!status.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
      return 2;
    }
  }
  request.timing = *timing;
  request.hold_at = absl::GetFlag(FLAGS_hold_at);
  request.source_bodies = *bodies;
  request.label = absl::StrFormat("%s, with the %s of %s", base->label.empty() ? base->name : base->label,
                                  absl::StrJoin(absl::GetFlag(FLAGS_parts), ", "), source->name);
  absl::StatusOr<MotionClip> spliced = SpliceParts(spec, *base, *source, request);
  if (!spliced.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(spliced.status().message()).c_str());
    return 1;
  }
  return WriteMadeClip(spec, out_dir, *spliced);
}

// Writes BASE with its path bent at --yaw_rate.
int Turn(const std::vector<std::string>& inputs, const HumanoidSpec& spec, const ImportOptions& options) {
  const std::string out_dir = absl::GetFlag(FLAGS_out);
  if (inputs.size() != 1 || out_dir.empty() || absl::GetFlag(FLAGS_name).empty()) {
    std::fprintf(stderr, "error: turn needs BASE --yaw_rate DEG_PER_S --name NAME --out DIR\n");
    return 2;
  }
  // TurnClip's own bound, checked here so that the message names the flag in its unit.
  const double degrees = absl::GetFlag(FLAGS_yaw_rate), max_degrees = kMaxTurnRate * 180.0 / M_PI;
  if (!(std::abs(degrees) <= max_degrees)) {
    std::fprintf(stderr, "error: --yaw_rate %g is not a finite rate within +-%g deg/s\n", degrees, max_degrees);
    return 2;
  }
  std::optional<MotionLibrary> library;
  absl::StatusOr<MotionClip> base = ResolveClip(inputs[0], spec, options, &library);
  if (!base.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(base.status().message()).c_str());
    return 2;
  }
  const TurnRequest request{absl::GetFlag(FLAGS_name), degrees * M_PI / 180.0, ""};
  absl::StatusOr<MotionClip> turned = TurnClip(spec, *base, request);
  if (!turned.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(turned.status().message()).c_str());
    return 1;
  }
  return WriteMadeClip(spec, out_dir, *turned);
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "imports, inspects, views, splices and turns motion clips, and makes held reach poses.\n"
      "  modskill-motion import IN... --out DIR [--labels CSV] [--fps 30] [--floor window|stance]\n"
      "  modskill-motion inspect FILE... [--fps 30] [--floor window|stance]\n"
      "  modskill-motion view CLIP... --html OUT.html  (CLIP: a motion file or a library clip name)\n"
      "  modskill-motion splice BASE SOURCE --parts R_Arm,L_Arm --name NAME --out DIR [--timing stretch|clip|hold [--hold_at 0.5]]\n"
      "  modskill-motion reach BASE --name NAME --out DIR [--count 32] [--seed 1] [--hand R_Hand] [--box_size 2] "
      "[--box_center 0,0,1]\n"
      "  modskill-motion turn BASE --yaw_rate 45 --name NAME --out DIR  (BASE's path bent at 45 deg/s, to the left)\n"
      "Formats: AMASS/SMPL(-H) .npz, CMU .bvh, DeepMimic humanoid3d .txt, native .msclip");
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  if (args.size() < 3) {
    std::fprintf(stderr,
                 "usage: modskill-motion import IN... --out DIR | modskill-motion inspect FILE... | "
                 "modskill-motion view CLIP... --html OUT.html | "
                 "modskill-motion splice BASE SOURCE --parts P,... --name NAME --out DIR | "
                 "modskill-motion reach BASE --name NAME --out DIR | "
                 "modskill-motion turn BASE --yaw_rate DEG_PER_S --name NAME --out DIR\n");
    return 2;
  }
  const std::string command = args[1];
  const std::vector<std::string> files(args.begin() + 2, args.end());
  auto spec = modskill::HumanoidSpec::LoadDefault();
  if (!spec.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(spec.status().message()).c_str());
    return 1;
  }
  // --fps, --ground and --floor, checked once for every command that reads motion files.
  const absl::StatusOr<modskill::ImportOptions> options = modskill::ImportOptionsFromFlags();
  if (!options.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(options.status().message()).c_str());
    return 2;
  }
  if (command == "import") return modskill::Import(files, *spec, *options);
  if (command == "inspect") return modskill::Inspect(files, *spec, *options);
  if (command == "view") return modskill::View(files, *spec, *options);
  if (command == "splice") return modskill::Splice(files, *spec, *options);
  if (command == "reach") return modskill::Reach(files, *spec, *options);
  if (command == "turn") return modskill::Turn(files, *spec, *options);
  std::fprintf(stderr, "error: unknown command '%s' (expected import, inspect, view, splice, reach or turn)\n",
               command.c_str());
  return 2;
}
