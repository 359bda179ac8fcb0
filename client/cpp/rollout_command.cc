#include "client/cpp/rollout_command.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <utility>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cpp/checkpoint_source.h"
#include "client/cpp/cli_output.h"
#include "common/atomic_file.h"
#include "common/viewer/viewer_wire.h"
#include "common/wire/tensor_codec.h"

namespace modskill::cli {
namespace {

using Json = nlohmann::ordered_json;

// A float32 as the shortest decimal that reads back to the same float (keeps frame JSON small).
double ShortestFloat(float value) {
  if (!std::isfinite(value)) return value;
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  *result.ptr = '\0';
  return std::strtod(buffer, nullptr);
}

struct Means {
  int clips = 0;
  double g_mpjpe = 0, mpjpe = 0, acc = 0, vel = 0;
  void Add(const v1::ClipMetrics& m) {
    ++clips;
    g_mpjpe += m.g_mpjpe_mm();
    mpjpe += m.mpjpe_mm();
    acc += m.acc_error_mm();
    vel += m.vel_error_mm();
  }
  // Means are null when there is no clip to average.
  Json ToJson() const {
    if (clips == 0) {
      return Json{{"clips", 0}, {"g_mpjpe_mm", nullptr}, {"mpjpe_mm", nullptr}, {"acc_error_mm", nullptr},
                  {"vel_error_mm", nullptr}};
    }
    const double n = clips;
    return Json{{"clips", clips},
                {"g_mpjpe_mm", g_mpjpe / n},
                {"mpjpe_mm", mpjpe / n},
                {"acc_error_mm", acc / n},
                {"vel_error_mm", vel / n}};
  }
  std::string Line() const {
    const double n = std::max(clips, 1);
    return absl::StrFormat("g-mpjpe %.2f mm, mpjpe %.2f mm, acc %.2f mm/frame^2, vel %.2f mm/frame", g_mpjpe / n,
                           mpjpe / n, acc / n, vel / n);
  }
};

// A missing --out directory is found before the rollout, not after.
absl::Status CheckOutDirectory(const std::string& out, const char* flag) {
  if (out.empty()) return absl::OkStatus();
  std::error_code error;
  const std::filesystem::path parent = std::filesystem::absolute(out, error).parent_path();
  if (error || !std::filesystem::is_directory(parent, error)) {
    return absl::NotFoundError(absl::StrCat(flag, ": ", out, ": the directory ", parent.string(), " does not exist"));
  }
  return absl::OkStatus();
}

// The request: the checkpoint's bytes (upload) or its absolute path, the clips, the frames.
// `checkpoint_shown`: how the checkpoint is named in the output.
absl::StatusOr<v1::RolloutRequest> MakeRequest(const RolloutOptions& options, std::string* checkpoint_shown) {
  v1::RolloutRequest request;
  if (absl::Status status = SetCheckpoint(options.checkpoint, options.upload, &request, checkpoint_shown); !status.ok()) {
    return status;
  }
  for (const std::string& clip : options.clips) request.add_clips(clip);
  request.set_stream_frames(options.frames || !options.html.empty());
  for (const auto& [name, value] : options.family_params) (*request.mutable_family_params())[name] = value;
  return request;
}

// The streamed frames, by clip in arrival order, as JSON rows; the first malformed frame stops
// the collection and is reported after the rollout.
class FrameCollector {
 public:
  void Add(const v1::RolloutFrame& frame) {
    if (!error_.ok()) return;
    std::vector<float> sim, ref;
    error_ = ReadFloatTensor(frame.sim_body_pos(), "RolloutFrame.sim_body_pos", &sim);
    if (error_.ok()) error_ = ReadFloatTensor(frame.ref_body_pos(), "RolloutFrame.ref_body_pos", &ref);
    if (error_.ok() && (sim.size() % 3 != 0 || sim.size() != ref.size())) {
      error_ = absl::DataLossError(absl::StrCat("RolloutFrame: ", sim.size(), " sim and ", ref.size(),
                                                " ref floats, expected [num_bodies, 3] each"));
    }
    if (!error_.ok()) return;
    auto positions = [](const std::vector<float>& flat) {
      Json rows = Json::array();
      for (size_t i = 0; i + 2 < flat.size(); i += 3) {
        rows.push_back({ShortestFloat(flat[i]), ShortestFloat(flat[i + 1]), ShortestFloat(flat[i + 2])});
      }
      return rows;
    };
    auto [it, inserted] = list_of_.emplace(frame.clip(), lists_.size());
    if (inserted) lists_.emplace_back(frame.clip(), Json::array());
    lists_[it->second].second.push_back(
        Json{{"frame", frame.frame()}, {"sim_body_pos", positions(sim)}, {"ref_body_pos", positions(ref)}});
    ++num_frames_;
  }

  // The clip's frames sorted by frame number (moved out; empty if none came).
  Json TakeSorted(const std::string& clip) {
    auto it = list_of_.find(clip);
    Json list = it == list_of_.end() ? Json::array() : std::move(lists_[it->second].second);
    std::stable_sort(list.begin(), list.end(),
                     [](const Json& a, const Json& b) { return a["frame"].get<int>() < b["frame"].get<int>(); });
    return list;
  }

  const absl::Status& error() const { return error_; }
  int64_t num_frames() const { return num_frames_; }

 private:
  std::vector<std::pair<std::string, Json>> lists_;
  std::map<std::string, size_t> list_of_;
  absl::Status error_;
  int64_t num_frames_ = 0;
};

// One line per clip, then the success rate and the means (over every clip, and over the
// successful ones when they differ).
void PrintMetrics(const std::vector<v1::ClipMetrics>& metrics, double seconds, Means& all, Means& succeeded) {
  size_t name_width = 4;
  for (const v1::ClipMetrics& m : metrics) name_width = std::max(name_width, m.clip().size());
  std::printf("%-*s  %7s  %6s  %9s  %9s  %8s  %8s\n", static_cast<int>(name_width), "clip", "success", "steps",
              "g-mpjpe", "mpjpe", "acc", "vel");
  for (const v1::ClipMetrics& m : metrics) {
    std::printf("%-*s  %7s  %6d  %9.2f  %9.2f  %8.2f  %8.2f\n", static_cast<int>(name_width), m.clip().c_str(),
                m.success() ? "yes" : "no", m.steps(), m.g_mpjpe_mm(), m.mpjpe_mm(), m.acc_error_mm(),
                m.vel_error_mm());
    all.Add(m);
    if (m.success()) succeeded.Add(m);
  }
  std::printf("(errors in mm: g-mpjpe global, mpjpe root-relative, acc mm/frame^2, vel mm/frame)\n");
  for (const v1::ClipMetrics& m : metrics) {
    if (!m.has_family()) continue;
    const v1::FamilyRolloutReport& f = m.family();
    std::map<std::string, double> params(f.params().begin(), f.params().end());
    std::string at;
    for (const auto& [name, value] : params) absl::StrAppend(&at, at.empty() ? "" : ", ", name, "=", value);
    std::printf("family at %s: F %.3f, root apex %.3f m, highest ankle/toe/wrist/hand %.3f m, flight %.2f s, "
                "%.1f clip frames played%s\n",
                at.c_str(), f.fitness(), f.apex_height_m(), f.highest_effector_m(), f.flight_s(), f.final_phase(),
                f.reached_end() ? " (reached the clip's end)" : " (ended before the clip's end)");
  }
  const int n = static_cast<int>(metrics.size());
  const double success_rate = n > 0 ? 100.0 * succeeded.clips / n : 0.0;
  if (n == 0) {
    std::printf("no clips evaluated\n");
  } else {
    std::printf("%d clip%s in %.1f s: success rate %.1f%% (%d/%d); mean %s\n", n, n == 1 ? "" : "s", seconds,
                success_rate, succeeded.clips, n, all.Line().c_str());
    if (succeeded.clips > 0 && succeeded.clips < n) {
      std::printf("mean over the %d successful clips: %s\n", succeeded.clips, succeeded.Line().c_str());
    }
  }
}

// One clip's metrics as JSON: per body by name when the sizes agree, per part by name when
// exactly one of the server's layouts has that many parts, else as raw lists.
Json ClipJson(const v1::ClipMetrics& m, const v1::EnvSpec& spec, const std::vector<v1::EnvSpec>& layouts) {
  Json clip{{"clip", m.clip()},
            {"success", m.success()},
            {"steps", m.steps()},
            {"g_mpjpe_mm", m.g_mpjpe_mm()},
            {"mpjpe_mm", m.mpjpe_mm()},
            {"acc_error_mm", m.acc_error_mm()},
            {"vel_error_mm", m.vel_error_mm()}};
  // Per body by name when the sizes agree, else as the raw list (body_names order).
  if (m.body_error_mm_size() == spec.body_names_size()) {
    Json bodies = Json::object();
    for (int b = 0; b < m.body_error_mm_size(); ++b) bodies[spec.body_names(b)] = m.body_error_mm(b);
    clip["body_error_mm"] = std::move(bodies);
  } else {
    clip["body_error_mm"] = std::vector<double>(m.body_error_mm().begin(), m.body_error_mm().end());
  }
  // Per part: named when exactly one of the server's layouts has that many parts.
  const v1::EnvSpec* part_layout = nullptr;
  int matches = 0;
  for (const v1::EnvSpec& layout : layouts) {
    if (layout.parts_size() == m.part_error_mm_size()) {
      part_layout = &layout;
      ++matches;
    }
  }
  if (matches == 1 && m.part_error_mm_size() > 0) {
    Json parts = Json::object();
    for (int p = 0; p < m.part_error_mm_size(); ++p) parts[part_layout->parts(p).name()] = m.part_error_mm(p);
    clip["part_layout"] = part_layout->part_layout();
    clip["part_error_mm"] = std::move(parts);
  } else {
    clip["part_error_mm"] = std::vector<double>(m.part_error_mm().begin(), m.part_error_mm().end());
  }
  if (m.has_family()) {
    const v1::FamilyRolloutReport& f = m.family();
    clip["family"] = Json{{"params", std::map<std::string, double>(f.params().begin(), f.params().end())},
                          {"fitness", f.fitness()},
                          {"apex_height_m", f.apex_height_m()},
                          {"highest_effector_m", f.highest_effector_m()},
                          {"flight_s", f.flight_s()},
                          {"reached_end", f.reached_end()},
                          {"final_phase", f.final_phase()}};
  }
  return clip;
}

// What --out holds: the run, the summary, and each clip (with its frames when streamed).
struct RolloutResult {
  std::string server;
  std::string checkpoint_shown;
  double seconds = 0;
  const std::vector<v1::ClipMetrics>* metrics = nullptr;
  Means all, succeeded;
};

int WriteJson(const RolloutOptions& options, const RolloutResult& result, const v1::EnvSpec& spec,
              const std::vector<v1::EnvSpec>& layouts, FrameCollector& frames) {
  const std::vector<v1::ClipMetrics>& metrics = *result.metrics;
  const int n = static_cast<int>(metrics.size());
  Json json;
  json["server"] = result.server;
  json["checkpoint"] = result.checkpoint_shown;
  json["uploaded"] = options.upload;
  json["body_names"] = std::vector<std::string>(spec.body_names().begin(), spec.body_names().end());
  Json summary = result.all.ToJson();
  summary["successes"] = result.succeeded.clips;
  summary["success_rate"] = n > 0 ? static_cast<double>(result.succeeded.clips) / n : 0.0;
  summary["successful"] = result.succeeded.ToJson();
  summary["seconds"] = result.seconds;
  json["summary"] = std::move(summary);
  Json clip_list = Json::array();
  for (const v1::ClipMetrics& m : metrics) {
    Json clip = ClipJson(m, spec, layouts);
    if (options.frames) clip["frames"] = frames.TakeSorted(m.clip());
    clip_list.push_back(std::move(clip));
  }
  json["clips"] = std::move(clip_list);
  // Frames make the file large: write it compact then.
  const std::string text = options.frames ? json.dump() : json.dump(2);
  if (absl::Status status = WriteFileAtomically(options.out, text + "\n"); !status.ok()) {
    return Fail(absl::StrCat("--out: ", status.message()));
  }
  std::printf("wrote %s: %s%s\n", options.out.c_str(), FormatBytes(text.size() + 1).c_str(),
              options.frames ? absl::StrCat(", ", frames.num_frames(), " frames").c_str() : "");
  return 0;
}

// The page's recorder, ready before the rollout runs.
absl::StatusOr<RolloutViewerRecorder> PageRecorder(SimulationClient& client, const v1::EnvSpec& spec) {
  auto motions = client.ListMotions();
  if (!motions.ok()) return motions.status();
  return PrepareRolloutPage(spec, *motions);
}

int WritePage(RolloutViewerRecorder& page, std::string title, const std::string& path) {
  absl::StatusOr<size_t> clips = WriteRolloutPage(page, std::move(title), path);
  if (!clips.ok()) return Fail(absl::StrCat("--html: ", clips.status().message()));
  std::printf("wrote %s: %zu clips, %lld frames\n", path.c_str(), *clips, static_cast<long long>(page.num_frames()));
  return 0;
}

}  // namespace

int Rollout(SimulationClient& client, const RolloutOptions& options) {
  const std::vector<std::string>& clips = options.clips;
  for (auto [path, flag] : {std::pair{&options.out, "--out"}, std::pair{&options.html, "--html"}}) {
    if (absl::Status status = CheckOutDirectory(*path, flag); !status.ok()) return Fail(status);
  }
  std::string checkpoint_shown;
  auto request = MakeRequest(options, &checkpoint_shown);
  if (!request.ok()) return Fail(request.status());

  // The body names (for per-body errors) and the part names of each layout (for per-part errors).
  auto spec = client.Describe();
  if (!spec.ok()) return Fail(spec.status());
  std::vector<v1::EnvSpec> layouts;
  if (!options.out.empty()) {
    for (const std::string& layout : spec->part_layouts()) {
      auto layout_spec = client.Describe(layout);
      if (!layout_spec.ok()) return Fail(layout_spec.status());
      layouts.push_back(*std::move(layout_spec));
    }
  }

  std::printf("rollout of %s%s on %s at %s\n", checkpoint_shown.c_str(), options.upload ? " (uploaded)" : "",
              clips.empty() ? "every clip"
                            : absl::StrCat(clips.size(), clips.size() == 1 ? " clip" : " clips").c_str(),
              client.server().c_str());
  std::fflush(stdout);

  FrameCollector frames;
  std::optional<RolloutViewerRecorder> page;
  if (!options.html.empty()) {
    absl::StatusOr<RolloutViewerRecorder> recorder = PageRecorder(client, *spec);
    if (!recorder.ok()) return Fail(absl::StrCat("--html: ", recorder.status().message()));
    page.emplace(*std::move(recorder));
  }
  std::function<void(const v1::RolloutFrame&)> on_frame = nullptr;
  if (options.frames || page) {
    on_frame = [&](const v1::RolloutFrame& frame) {
      if (options.frames) frames.Add(frame);
      if (page) page->Add(frame);
    };
  }
  const auto start = std::chrono::steady_clock::now();
  auto metrics = client.Rollout(*request, on_frame);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!metrics.ok()) return Fail(metrics.status());
  if (!frames.error().ok()) return Fail(frames.error());
  if (page) {
    // A family at other body proportions: its limbs as the server stretched them.
    if (metrics->size() == 1 && metrics->front().has_family()) {
      const auto& params = metrics->front().family().params();
      page->ScaleFamilyLimbs(params.count("leg_scale") ? params.at("leg_scale") : 1.0,
                             params.count("arm_scale") ? params.at("arm_scale") : 1.0);
    }
    if (int code = WritePage(*page, absl::StrCat("rollout of ", checkpoint_shown), options.html); code != 0) return code;
  }

  RolloutResult result;
  result.server = client.server();
  result.checkpoint_shown = checkpoint_shown;
  result.seconds = seconds;
  result.metrics = &*metrics;
  PrintMetrics(*metrics, seconds, result.all, result.succeeded);
  if (options.out.empty()) return 0;
  return WriteJson(options, result, *spec, layouts, frames);
}

}  // namespace modskill::cli
