#include "client/cpp/skill_commands.h"

#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <utility>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/cpp/cli_output.h"
#include "client/cpp/skill_frames.h"
#include "common/atomic_file.h"
#include "common/viewer/viewer_wire.h"

namespace modskill::cli {
namespace {

using Json = nlohmann::ordered_json;

absl::StatusOr<v1::RolloutRequest> SkillRequest(const SkillOptions& options) {
  v1::RolloutRequest request;
  auto bytes = ReadFileToString(options.checkpoint, size_t{512} << 20);
  if (!bytes.ok()) return absl::Status(bytes.status().code(), absl::StrCat("--checkpoint: ", bytes.status().message()));
  request.set_checkpoint_bytes(*std::move(bytes));
  request.set_record_skills(true);
  request.set_stream_frames(true);
  request.set_max_steps_per_clip(options.max_steps);
  return request;
}

struct Recorded {
  std::vector<v1::ClipMetrics> metrics;
  std::vector<SkillTrack> tracks;
};

// One Rollout with its frames collected (and shown to `also` when set).
absl::StatusOr<Recorded> RunRecorded(SimulationClient& client, const v1::RolloutRequest& request,
                                     const std::function<void(const v1::RolloutFrame&)>& also = nullptr) {
  SkillTrackCollector collector;
  auto metrics = client.Rollout(request, [&](const v1::RolloutFrame& frame) {
    collector.Add(frame);
    if (also) also(frame);
  });
  if (!metrics.ok()) return metrics.status();
  if (!collector.error().ok()) return collector.error();
  return Recorded{*std::move(metrics), std::move(collector.tracks())};
}

absl::StatusOr<std::vector<v1::EnvSpec>> AllLayouts(SimulationClient& client) {
  auto spec = client.Describe();
  if (!spec.ok()) return spec.status();
  std::vector<v1::EnvSpec> layouts;
  for (const std::string& layout : spec->part_layouts()) {
    auto described = client.Describe(layout);
    if (!described.ok()) return described.status();
    layouts.push_back(*std::move(described));
  }
  return layouts;
}

Json MetricsJson(const v1::ClipMetrics& m) {
  Json json{{"clip", m.clip()},         {"success", m.success()},   {"steps", m.steps()},
            {"g_mpjpe_mm", m.g_mpjpe_mm()}, {"mpjpe_mm", m.mpjpe_mm()}, {"max_mean_body_error_m", m.max_mean_body_error_m()}};
  if (m.has_composition()) {
    const v1::CompositionReport& c = m.composition();
    json["composition"] = Json{{"source_clip", c.source_clip()},
                               {"parts", std::vector<std::string>(c.parts().begin(), c.parts().end())},
                               {"mode", v1::CompositionMode_Name(c.mode())},
                               {"source_steps", c.source_steps()},
                               {"source_terminated", c.source_terminated()},
                               {"held_steps", c.held_steps()}};
  }
  return json;
}

// A track's frames: z per part, body positions, and the speed of each of `parts`.
Json FramesJson(const SkillTrack& track, const PartBodies& layout, const std::vector<std::string>& parts, double dt) {
  std::vector<std::vector<double>> speed, local;
  for (const std::string& part : parts) {
    const size_t p = std::find(layout.names.begin(), layout.names.end(), part) - layout.names.begin();
    speed.push_back(PartSpeed(track, layout.bodies[p], dt, false));
    local.push_back(PartSpeed(track, layout.bodies[p], dt, true));
  }
  Json frames = Json::array();
  for (size_t f = 0; f < track.frame.size(); ++f) {
    Json z = Json::array();
    for (int p = 0; p < track.parts && !track.z[f].empty(); ++p) {
      z.push_back(FloatRow(std::vector<float>(track.z[f].begin() + p * track.embed_dim,
                                              track.z[f].begin() + (p + 1) * track.embed_dim)));
    }
    Json part_speed = Json::object(), part_local = Json::object();
    for (size_t i = 0; i < parts.size(); ++i) {
      part_speed[parts[i]] = speed[i][f];
      part_local[parts[i]] = local[i][f];
    }
    frames.push_back(Json{{"frame", track.frame[f]},
                          {"z", std::move(z)},
                          {"part_speed_mps", std::move(part_speed)},
                          {"part_root_relative_speed_mps", std::move(part_local)},
                          {"sim_body_pos", FloatRow(track.body_pos[f])}});
  }
  return frames;
}

int WriteJsonFile(const std::string& path, const Json& json) {
  const std::string text = json.dump() + "\n";
  if (absl::Status status = WriteFileAtomically(path, text); !status.ok()) return Fail(status);
  std::printf("wrote %s: %s\n", path.c_str(), FormatBytes(text.size()).c_str());
  return 0;
}

absl::Status CheckOutDir(const std::string& dir) {
  std::error_code error;
  if (dir.empty() || !std::filesystem::is_directory(dir, error)) {
    return absl::NotFoundError(absl::StrCat("--out: '", dir, "' is not a directory"));
  }
  return absl::OkStatus();
}

}  // namespace

int RecordSkills(SimulationClient& client, const SkillOptions& options) {
  if (absl::Status status = CheckOutDir(options.out_dir); !status.ok()) return Fail(status);
  auto request = SkillRequest(options);
  if (!request.ok()) return Fail(request.status());
  for (const std::string& clip : options.clips) request->add_clips(clip);
  auto recorded = RunRecorded(client, *request);
  if (!recorded.ok()) return Fail(recorded.status());
  auto layouts = AllLayouts(client);
  if (!layouts.ok()) return Fail(layouts.status());
  const int parts = recorded->tracks.empty() ? 0 : recorded->tracks[0].parts;
  auto layout = FindPartLayout(*layouts, parts, {});
  if (!layout.ok()) return Fail(layout.status());
  Json clips = Json::array();
  std::vector<std::vector<float>> rows;
  Json labels = Json::array();
  for (size_t c = 0; c < recorded->tracks.size(); ++c) {
    const SkillTrack& track = recorded->tracks[c];
    Json z = Json::array();
    for (size_t f = 0; f < track.z.size(); ++f) {
      if (track.z[f].empty()) continue;
      Json frame = Json::array();
      for (int p = 0; p < track.parts; ++p) {
        rows.emplace_back(track.z[f].begin() + p * track.embed_dim, track.z[f].begin() + (p + 1) * track.embed_dim);
        frame.push_back(FloatRow(rows.back()));
        labels.push_back(Json{{"clip", track.clip}, {"part", layout->names[p]}, {"frame", track.frame[f]}});
      }
      z.push_back(std::move(frame));
    }
    Json clip = c < recorded->metrics.size() ? MetricsJson(recorded->metrics[c]) : Json{{"clip", track.clip}};
    clip["z"] = std::move(z);
    clips.push_back(std::move(clip));
  }
  auto pca = PrincipalPlane(rows);
  if (!pca.ok()) return Fail(pca.status());
  for (size_t i = 0; i < labels.size(); ++i) {
    labels[i]["x"] = pca->points[i][0];
    labels[i]["y"] = pca->points[i][1];
  }
  Json json{{"checkpoint", options.checkpoint}, {"server", client.server()}, {"part_layout", layout->layout},
            {"parts", layout->names}, {"embed_dim", recorded->tracks.empty() ? 0 : recorded->tracks[0].embed_dim},
            {"clips", std::move(clips)},
            {"pca", Json{{"explained_variance", {pca->explained[0], pca->explained[1]}}, {"points", std::move(labels)}}}};
  std::printf("recorded z of %zu parts on %zu clips (%zu vectors); PCA plane explains %.1f%% + %.1f%%\n",
              layout->names.size(), recorded->tracks.size(), rows.size(), 100 * pca->explained[0],
              100 * pca->explained[1]);
  return WriteJsonFile(options.out_dir + "/skills.json", json);
}

int Compose(SimulationClient& client, const SkillOptions& options) {
  if (absl::Status status = CheckOutDir(options.out_dir); !status.ok()) return Fail(status);
  auto request = SkillRequest(options);
  if (!request.ok()) return Fail(request.status());
  auto spec = client.Describe();
  if (!spec.ok()) return Fail(spec.status());
  auto motions = client.ListMotions();
  if (!motions.ok()) return Fail(motions.status());
  auto page = PrepareRolloutPage(*spec, *motions);
  if (!page.ok()) return Fail(absl::StrCat("viewer page: ", page.status().message()));
  // Three rollouts, named apart in the viewer: the composition, then base and source alone.
  v1::RolloutRequest composed = *request;
  v1::SkillComposition* composition = composed.mutable_composition();
  composition->set_base_clip(options.base);
  composition->set_source_clip(options.source);
  for (const std::string& part : options.parts) composition->add_parts(part);
  composition->set_mode(options.interpolate ? v1::INTERPOLATE : v1::SWAP);
  const std::string names[3] = {"composed", absl::StrCat("base_", options.base), absl::StrCat("source_", options.source)};
  std::vector<Recorded> runs;
  for (int r = 0; r < 3; ++r) {
    v1::RolloutRequest run = composed;
    if (r > 0) {
      run.clear_composition();
      run.add_clips(r == 1 ? options.base : options.source);
    }
    auto recorded = RunRecorded(client, run, [&](const v1::RolloutFrame& frame) {
      v1::RolloutFrame renamed = frame;
      renamed.set_clip(names[r]);
      page->Add(renamed);
    });
    if (!recorded.ok()) return Fail(recorded.status());
    runs.push_back(*std::move(recorded));
  }
  auto layouts = AllLayouts(client);
  if (!layouts.ok()) return Fail(layouts.status());
  auto layout = FindPartLayout(*layouts, runs[0].tracks.at(0).parts, options.parts);
  if (!layout.ok()) return Fail(layout.status());
  Json rollouts = Json::object(), part_bodies = Json::object();
  for (const std::string& part : options.parts) {
    const size_t p = std::find(layout->names.begin(), layout->names.end(), part) - layout->names.begin();
    Json bodies = Json::array();
    for (int b : layout->bodies[p]) bodies.push_back(spec->body_names(b));
    part_bodies[part] = std::move(bodies);
  }
  const char* keys[3] = {"composed", "base", "source"};
  for (int r = 0; r < 3; ++r) {
    Json rollout = MetricsJson(runs[r].metrics.at(0));
    rollout["viewer_clip"] = names[r];
    rollout["frames"] = FramesJson(runs[r].tracks.at(0), *layout, options.parts, spec->control_dt());
    rollouts[keys[r]] = std::move(rollout);
  }
  const v1::ClipMetrics& m = runs[0].metrics[0];
  std::printf("composed %s onto %s (%s of %s): %s, %d steps%s; source %d steps%s, %d steps held\n",
              absl::StrJoin(options.parts, ",").c_str(), options.base.c_str(), options.interpolate ? "interpolated" : "swapped",
              options.source.c_str(), m.success() ? "stayed up" : "terminated", m.steps(),
              m.success() ? "" : " (mean body error > 0.5 m)", m.composition().source_steps(),
              m.composition().source_terminated() ? " (terminated)" : "", m.composition().held_steps());
  Json json{{"checkpoint", options.checkpoint}, {"server", client.server()}, {"base", options.base},
            {"source", options.source}, {"parts", options.parts}, {"mode", options.interpolate ? "INTERPOLATE" : "SWAP"},
            {"part_layout", layout->layout}, {"control_dt", spec->control_dt()}, {"part_bodies", std::move(part_bodies)},
            {"body_names", std::vector<std::string>(spec->body_names().begin(), spec->body_names().end())},
            {"rollouts", std::move(rollouts)}};
  if (int code = WriteJsonFile(options.out_dir + "/compose.json", json); code != 0) return code;
  const std::string html = options.out_dir + "/compose.html";
  auto clips = WriteRolloutPage(*page, absl::StrCat("composition: ", names[0], " = ", options.base, " with ",
                                                    absl::StrJoin(options.parts, ","), " from ", options.source),
                                html);
  if (!clips.ok()) return Fail(absl::StrCat("viewer page: ", clips.status().message()));
  std::printf("wrote %s: %zu rollouts (%s)\n", html.c_str(), *clips, absl::StrJoin(names, ", ").c_str());
  return 0;
}

}  // namespace modskill::cli
