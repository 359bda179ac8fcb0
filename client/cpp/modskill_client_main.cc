// modskill-client: the command line of a modskill simulation server (see
// proto/modskill/v1/modskill.proto): the env spec, the motion library, server stats, uploads,
// checkpoint evaluation (rollout) and a stepping throughput check (simulate).
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/time.h"
#include "client/cpp/simulation_client.h"
#include "common/atomic_file.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "server address, host:port");
ABSL_FLAG(std::string, auth_token_file, "", "file holding the server's token (sent as 'authorization: Bearer <token>')");
ABSL_FLAG(std::string, tls_ca, "", "PEM root certificates: connect with TLS, trusting these roots");
ABSL_FLAG(std::string, tls_server_name, "", "name to check in the server certificate (default: the host of --server)");
ABSL_FLAG(double, timeout_s, 10, "seconds to wait for the server to answer when connecting");
ABSL_FLAG(std::string, part_layout, "", "describe, simulate: part layout (empty: the server's default)");
ABSL_FLAG(std::string, checkpoint, "",
          "rollout: TorchScript checkpoint; a path the server reads (relative paths are made absolute here), "
          "or with --upload a local file whose bytes are sent");
ABSL_FLAG(std::vector<std::string>, clip, {},
          "rollout, simulate: clip names, repeated or comma-separated (empty: every clip)");
ABSL_FLAG(std::string, out, "", "rollout: write metrics, per-body errors (and frames) as JSON to this file");
ABSL_FLAG(bool, upload, true,
          "rollout: send the checkpoint file's bytes; false: send its path, which the server reads only from its "
          "--checkpoint_dir directories");
ABSL_FLAG(bool, frames, false, "rollout: stream per-frame simulated and reference body positions into --out");
ABSL_FLAG(int, envs, 16, "simulate: envs in the session");
ABSL_FLAG(int, steps, 100, "simulate: steps to take");
ABSL_FLAG(std::string, actions, "zero", "simulate: zero or random (uniform in [-1, 1])");
ABSL_FLAG(uint64_t, seed, 1, "simulate: seed of the session and of the random actions");

namespace modskill {
namespace {

using Json = nlohmann::ordered_json;

constexpr char kUsage[] = R"(usage: modskill-client <command> [flags] [args]

commands:
  describe [--part_layout 5part]   the env spec: sizes, control dt, layouts, one line per body part
  motions                          the server's motion library, one line per clip
  stats                            server totals, live sessions and their 5 most sampled clips
  add-motions FILE...              upload clips (.npz .bvh .txt .msclip) to the server's library
  rollout --checkpoint F [--clip NAME...] [--out F.json] [--upload] [--frames]
                                   evaluate a TorchScript policy on clips (default: every clip)
  simulate [--envs N] [--steps K] [--actions zero|random] [--seed S] [--part_layout L] [--clip NAME...]
                                   step a session and report env steps/s, reward, message sizes

common flags:
  --server host:port (127.0.0.1:50051)  --auth_token_file F  --tls_ca F  --tls_server_name NAME
  --timeout_s S (10)
'modskill-client --help' lists every flag.)";

constexpr int kUsageError = 2;
constexpr int kRuntimeError = 1;

int Usage(const std::string& message) {
  std::fprintf(stderr, "error: %s\n\n%s\n", message.c_str(), kUsage);
  return kUsageError;
}

int Fail(const absl::Status& status) {
  std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
  return kRuntimeError;
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return kRuntimeError;
}

// absl keeps only the last of repeated flags and exits with 1 on a bad one. This pass runs first:
// it collects every --clip value (repeated and comma-separated) and reports an unknown flag or a
// malformed value as a usage error.
bool PrescanFlags(int argc, char** argv, std::vector<std::string>* clips, std::string* error) {
  for (int i = 1; i < argc; ++i) {
    absl::string_view arg = argv[i];
    if (arg == "--") break;
    if (arg.size() < 2 || arg[0] != '-') continue;
    arg.remove_prefix(arg[1] == '-' ? 2 : 1);
    absl::string_view name = arg;
    absl::string_view value;
    bool has_value = false;
    if (const size_t eq = arg.find('='); eq != absl::string_view::npos) {
      name = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_value = true;
    }
    // absl's usage pseudo-flags (--help, --helpfull, ...) are left to absl.
    static const char* const kUsageFlags[] = {"help",    "helpfull", "helpshort",      "helppackage",
                                              "helpon",  "helpmatch", "only_check_args", "version"};
    if (std::find(std::begin(kUsageFlags), std::end(kUsageFlags), name) != std::end(kUsageFlags)) continue;
    absl::CommandLineFlag* flag = absl::FindCommandLineFlag(name);
    if (flag == nullptr && !has_value && absl::StartsWith(name, "no")) {
      absl::CommandLineFlag* negated = absl::FindCommandLineFlag(name.substr(2));
      if (negated != nullptr && negated->IsOfType<bool>()) continue;  // --noupload
    }
    if (flag == nullptr) {
      *error = absl::StrCat("unknown flag --", name);
      return false;
    }
    if (!has_value) {
      if (flag->IsOfType<bool>()) continue;
      if (i + 1 >= argc) {
        *error = absl::StrCat("--", name, " needs a value");
        return false;
      }
      value = argv[++i];
    }
    // absl's own flags (flagfile, fromenv, ...) are left to absl.
    if (name == "flagfile" || name == "fromenv" || name == "tryfromenv" || name == "undefok") continue;
    std::string parse_error;
    if (!flag->ParseFrom(value, &parse_error)) {
      *error = absl::StrCat("--", name, ": ", parse_error);
      return false;
    }
    if (name == "clip") {
      for (absl::string_view clip : absl::StrSplit(value, ',', absl::SkipWhitespace())) clips->emplace_back(clip);
    }
  }
  return true;
}

std::string FormatBytes(size_t bytes) {
  if (bytes < 1024) return absl::StrCat(bytes, " B");
  if (bytes < (size_t{1} << 20)) return absl::StrFormat("%.1f KiB (%d B)", bytes / 1024.0, bytes);
  return absl::StrFormat("%.1f MiB (%d B)", bytes / 1048576.0, bytes);
}

// A float32 as the shortest decimal that reads back to the same float (keeps frame JSON small).
double ShortestFloat(float value) {
  if (!std::isfinite(value)) return value;
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  *result.ptr = '\0';
  return std::strtod(buffer, nullptr);
}

absl::StatusOr<std::unique_ptr<SimulationClient>> Connect() {
  ClientOptions options;
  options.server = absl::GetFlag(FLAGS_server);
  options.tls_ca_file = absl::GetFlag(FLAGS_tls_ca);
  options.tls_server_name = absl::GetFlag(FLAGS_tls_server_name);
  options.connect_timeout = absl::Seconds(absl::GetFlag(FLAGS_timeout_s));
  if (!absl::GetFlag(FLAGS_auth_token_file).empty()) {
    auto token = ReadTokenFile(absl::GetFlag(FLAGS_auth_token_file));
    if (!token.ok()) return absl::Status(token.status().code(), absl::StrCat("--auth_token_file: ", token.status().message()));
    options.token = *std::move(token);
  }
  auto client = SimulationClient::Connect(options);
  if (!client.ok() && absl::StartsWith(client.status().message(), "tls_ca:")) {
    return absl::Status(client.status().code(), absl::StrCat("--", client.status().message()));
  }
  return client;
}

// ---------------------------------------------------------------------------------------------

int Describe(SimulationClient& client) {
  auto spec = client.Describe(absl::GetFlag(FLAGS_part_layout));
  if (!spec.ok()) return Fail(spec.status());
  const int amp_frames = spec->amp_history();
  std::printf("env spec of %s, part layout %s\n", client.server().c_str(), spec->part_layout().c_str());
  std::printf("  observation   %d floats = self %d + task %d\n", spec->obs_size(), spec->self_obs_size(),
              spec->task_obs_size());
  std::printf("  action        %d floats (PD targets, hinges in action order)\n", spec->action_size());
  std::printf("  AMP           %d floats per frame x %d frames = %d\n", spec->amp_obs_per_frame(), amp_frames,
              spec->amp_obs_per_frame() * amp_frames);
  std::printf("  control dt    %.6g s (%.4g Hz)\n", spec->control_dt(),
              spec->control_dt() > 0 ? 1.0 / spec->control_dt() : 0.0);
  std::printf("  bodies        %d, joints %d, clips in the library %d\n", spec->body_names_size(),
              spec->joint_names_size(), spec->num_motions());
  std::printf("  reward terms  %s\n", absl::StrJoin(spec->reward_terms(), " ").c_str());
  std::printf("  layouts       %s\n", absl::StrJoin(spec->part_layouts(), " ").c_str());
  size_t name_width = 4;
  for (const v1::BodyPart& part : spec->parts()) name_width = std::max(name_width, part.name().size());
  std::printf("parts (%d):\n", spec->parts_size());
  std::printf("  %-*s  %9s %5s  %12s %5s  %s\n", static_cast<int>(name_width), "part", "obs start", "size",
              "action start", "size", "bodies");
  for (const v1::BodyPart& part : spec->parts()) {
    std::printf("  %-*s  %9d %5d  %12d %5d  %s\n", static_cast<int>(name_width), part.name().c_str(),
                part.obs().start(), part.obs().size(), part.action().start(), part.action().size(),
                absl::StrJoin(part.bodies(), " ").c_str());
  }
  return 0;
}

int Motions(SimulationClient& client) {
  auto motions = client.ListMotions();
  if (!motions.ok()) return Fail(motions.status());
  size_t name_width = 4;
  for (const v1::MotionInfo& m : motions->motions()) name_width = std::max(name_width, m.name().size());
  std::printf("%-*s  %6s  %6s  %9s  %-9s  %s\n", static_cast<int>(name_width), "name", "frames", "fps", "duration",
              "humanml3d", "label");
  double total = 0;
  for (const v1::MotionInfo& m : motions->motions()) {
    std::printf("%-*s  %6d  %6.2f  %7.2f s  %-9s  %s\n", static_cast<int>(name_width), m.name().c_str(), m.frames(),
                m.fps(), m.duration(), m.humanml3d_id().empty() ? "-" : m.humanml3d_id().c_str(),
                m.label().empty() ? "-" : m.label().c_str());
    total += m.duration();
  }
  std::printf("%d clips, %.1f s in all\n", motions->motions_size(), total);
  return 0;
}

int Stats(SimulationClient& client) {
  auto stats = client.GetStats();
  if (!stats.ok()) return Fail(stats.status());
  std::printf("server %s: up %s, %d clips\n", client.server().c_str(),
              absl::FormatDuration(absl::Seconds(std::floor(stats->uptime_seconds()))).c_str(), stats->num_motions());
  std::printf("  sessions         %d active, %lld opened\n", stats->active_sessions(),
              static_cast<long long>(stats->sessions_opened()));
  std::printf("  env steps        %lld (%.1f env steps/s lately)\n", static_cast<long long>(stats->env_steps()),
              stats->env_steps_per_second());
  std::printf("  episodes         %lld\n", static_cast<long long>(stats->episodes()));
  std::printf("  physics resets   %lld\n", static_cast<long long>(stats->physics_resets()));
  std::printf("  failure reports  %lld\n", static_cast<long long>(stats->failure_reports()));
  if (stats->sessions_size() == 0) {
    std::printf("no live sessions\n");
    return 0;
  }
  size_t id_width = 7, peer_width = 4;
  for (const v1::SessionStats& s : stats->sessions()) {
    id_width = std::max(id_width, s.session_id().size());
    peer_width = std::max(peer_width, s.peer().size());
  }
  std::printf("live sessions (%d):\n", stats->sessions_size());
  std::printf("  %-*s  %-*s  %6s  %10s  %10s  %9s  %7s  %8s\n", static_cast<int>(id_width), "session",
              static_cast<int>(peer_width), "peer", "envs", "steps", "steps/s", "episodes", "resets", "reports");
  for (const v1::SessionStats& s : stats->sessions()) {
    std::printf("  %-*s  %-*s  %6d  %10lld  %10.1f  %9lld  %7lld  %8lld\n", static_cast<int>(id_width),
                s.session_id().c_str(), static_cast<int>(peer_width), s.peer().c_str(), s.num_envs(),
                static_cast<long long>(s.steps()), s.steps_per_second(), static_cast<long long>(s.episodes()),
                static_cast<long long>(s.physics_resets()), static_cast<long long>(s.failure_reports()));
  }
  // The adaptive sampler: the clips each session draws most often.
  constexpr int kTopClips = 5;
  for (const v1::SessionStats& s : stats->sessions()) {
    if (s.clips_size() == 0) continue;
    std::vector<int> order(s.clips_size());
    for (int c = 0; c < s.clips_size(); ++c) order[c] = c;
    const size_t shown = std::min<size_t>(kTopClips, order.size());
    // Highest probability first; ties (uniform sampling) keep the session's clip order.
    std::partial_sort(order.begin(), order.begin() + shown, order.end(), [&](int a, int b) {
      const double pa = s.clips(a).probability(), pb = s.clips(b).probability();
      return pa != pb ? pa > pb : a < b;
    });
    std::vector<const v1::ClipSamplingState*> clips;
    for (size_t c = 0; c < shown; ++c) clips.push_back(&s.clips(order[c]));
    size_t name_width = 4;
    for (size_t c = 0; c < shown; ++c) name_width = std::max(name_width, clips[c]->clip().size());
    std::printf("session %s: top %zu of %d clips by sampling probability (uniform %.4f):\n", s.session_id().c_str(),
                shown, s.clips_size(), 1.0 / s.clips_size());
    std::printf("  %-*s  %11s  %10s  %9s  %9s\n", static_cast<int>(name_width), "clip", "probability", "weight",
                "failures", "successes");
    for (size_t c = 0; c < shown; ++c) {
      std::printf("  %-*s  %11.4f  %10.4g  %9lld  %9lld\n", static_cast<int>(name_width), clips[c]->clip().c_str(),
                  clips[c]->probability(), clips[c]->weight(), static_cast<long long>(clips[c]->failures()),
                  static_cast<long long>(clips[c]->successes()));
    }
    const v1::GenerationStats& g = s.generation();
    if (!g.enabled()) {
      std::printf("  generative resampling off\n");
      continue;
    }
    std::string rejects;
    for (const auto& [check, count] : g.rejected_by_check()) {
      absl::StrAppend(&rejects, rejects.empty() ? " (" : ", ", check, " ", count);
    }
    if (!rejects.empty()) rejects += ")";
    std::printf("  generated clips: %d live, %lld made in %lld rounds, %lld rejected%s, %lld evicted\n",
                g.live_generated_clips(), static_cast<long long>(g.generated()), static_cast<long long>(g.requests()),
                static_cast<long long>(g.rejected()), rejects.c_str(), static_cast<long long>(g.evicted()));
    if (g.generator_errors() > 0) {
      std::printf("  external generator: %lld errors (%lld built-in fallbacks), last: %s\n",
                  static_cast<long long>(g.generator_errors()), static_cast<long long>(g.builtin_fallbacks()),
                  g.last_generator_error().c_str());
    }
  }
  return 0;
}

int AddMotions(SimulationClient& client, const std::vector<std::string>& files) {
  auto added = client.AddMotionFiles(files);
  if (!added.ok()) return Fail(added.status());
  std::printf("added %d clip%s to %s:\n", added->added_size(), added->added_size() == 1 ? "" : "s",
              client.server().c_str());
  for (const v1::MotionInfo& m : added->added()) {
    std::printf("  %s: %d frames at %.2f fps (%.2f s)%s%s%s\n", m.name().c_str(), m.frames(), m.fps(), m.duration(),
                m.source().empty() ? "" : absl::StrCat(", from ", m.source()).c_str(),
                m.label().empty() ? "" : ", label: ", m.label().c_str());
  }
  return 0;
}

// ---------------------------------------------------------------------------------------------

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

int Rollout(SimulationClient& client, const std::vector<std::string>& clips) {
  const std::string checkpoint = absl::GetFlag(FLAGS_checkpoint);
  const std::string out = absl::GetFlag(FLAGS_out);
  const bool upload = absl::GetFlag(FLAGS_upload);
  const bool frames = absl::GetFlag(FLAGS_frames);

  // A missing --out directory is found before the rollout, not after.
  if (!out.empty()) {
    std::error_code error;
    const std::filesystem::path parent = std::filesystem::absolute(out, error).parent_path();
    if (error || !std::filesystem::is_directory(parent, error)) {
      return Fail(absl::StrCat("--out: ", out, ": the directory ", parent.string(), " does not exist"));
    }
  }

  v1::RolloutRequest request;
  std::string checkpoint_shown = checkpoint;
  if (upload) {
    auto bytes = ReadFileToString(checkpoint, size_t{512} << 20);
    if (!bytes.ok()) return Fail(absl::StrCat("--checkpoint: ", bytes.status().message()));
    request.set_checkpoint_bytes(*std::move(bytes));
  } else {
    std::error_code error;
    std::filesystem::path path = std::filesystem::absolute(checkpoint, error);
    checkpoint_shown = error ? checkpoint : path.lexically_normal().string();
    request.set_checkpoint_path(checkpoint_shown);
  }
  for (const std::string& clip : clips) request.add_clips(clip);
  request.set_stream_frames(frames);

  // The body names (for per-body errors) and the part names of each layout (for per-part errors).
  auto spec = client.Describe();
  if (!spec.ok()) return Fail(spec.status());
  std::vector<v1::EnvSpec> layouts;
  if (!out.empty()) {
    for (const std::string& layout : spec->part_layouts()) {
      auto layout_spec = client.Describe(layout);
      if (!layout_spec.ok()) return Fail(layout_spec.status());
      layouts.push_back(*std::move(layout_spec));
    }
  }

  std::printf("rollout of %s%s on %s at %s\n", checkpoint_shown.c_str(), upload ? " (uploaded)" : "",
              clips.empty() ? "every clip"
                            : absl::StrCat(clips.size(), clips.size() == 1 ? " clip" : " clips").c_str(),
              client.server().c_str());
  std::fflush(stdout);

  // Frames by clip, in arrival order.
  std::vector<std::pair<std::string, Json>> frame_lists;
  std::map<std::string, size_t> frame_list_of;
  absl::Status frame_error;
  int64_t num_frames = 0;
  std::function<void(const v1::RolloutFrame&)> on_frame = nullptr;
  if (frames) {
    on_frame = [&](const v1::RolloutFrame& frame) {
      if (!frame_error.ok()) return;
      std::vector<float> sim, ref;
      frame_error = DecodeFloatTensor(frame.sim_body_pos(), "RolloutFrame.sim_body_pos", &sim);
      if (frame_error.ok()) frame_error = DecodeFloatTensor(frame.ref_body_pos(), "RolloutFrame.ref_body_pos", &ref);
      if (frame_error.ok() && (sim.size() % 3 != 0 || sim.size() != ref.size())) {
        frame_error = absl::DataLossError(absl::StrCat("RolloutFrame: ", sim.size(), " sim and ", ref.size(),
                                                       " ref floats, expected [num_bodies, 3] each"));
      }
      if (!frame_error.ok()) return;
      auto positions = [](const std::vector<float>& flat) {
        Json rows = Json::array();
        for (size_t i = 0; i + 2 < flat.size(); i += 3) {
          rows.push_back({ShortestFloat(flat[i]), ShortestFloat(flat[i + 1]), ShortestFloat(flat[i + 2])});
        }
        return rows;
      };
      auto [it, inserted] = frame_list_of.emplace(frame.clip(), frame_lists.size());
      if (inserted) frame_lists.emplace_back(frame.clip(), Json::array());
      frame_lists[it->second].second.push_back(
          Json{{"frame", frame.frame()}, {"sim_body_pos", positions(sim)}, {"ref_body_pos", positions(ref)}});
      ++num_frames;
    };
  }

  const auto start = std::chrono::steady_clock::now();
  auto metrics = client.Rollout(request, on_frame);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!metrics.ok()) return Fail(metrics.status());
  if (!frame_error.ok()) return Fail(frame_error);

  size_t name_width = 4;
  for (const v1::ClipMetrics& m : *metrics) name_width = std::max(name_width, m.clip().size());
  std::printf("%-*s  %7s  %6s  %9s  %9s  %8s  %8s\n", static_cast<int>(name_width), "clip", "success", "steps",
              "g-mpjpe", "mpjpe", "acc", "vel");
  Means all, succeeded;
  for (const v1::ClipMetrics& m : *metrics) {
    std::printf("%-*s  %7s  %6d  %9.2f  %9.2f  %8.2f  %8.2f\n", static_cast<int>(name_width), m.clip().c_str(),
                m.success() ? "yes" : "no", m.steps(), m.g_mpjpe_mm(), m.mpjpe_mm(), m.acc_error_mm(),
                m.vel_error_mm());
    all.Add(m);
    if (m.success()) succeeded.Add(m);
  }
  std::printf("(errors in mm: g-mpjpe global, mpjpe root-relative, acc mm/frame^2, vel mm/frame)\n");
  const int n = static_cast<int>(metrics->size());
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

  if (out.empty()) return 0;
  Json json;
  json["server"] = client.server();
  json["checkpoint"] = checkpoint_shown;
  json["uploaded"] = upload;
  json["body_names"] = std::vector<std::string>(spec->body_names().begin(), spec->body_names().end());
  Json summary = all.ToJson();
  summary["successes"] = succeeded.clips;
  summary["success_rate"] = n > 0 ? static_cast<double>(succeeded.clips) / n : 0.0;
  summary["successful"] = succeeded.ToJson();
  summary["seconds"] = seconds;
  json["summary"] = std::move(summary);
  Json clip_list = Json::array();
  for (const v1::ClipMetrics& m : *metrics) {
    Json clip{{"clip", m.clip()},
              {"success", m.success()},
              {"steps", m.steps()},
              {"g_mpjpe_mm", m.g_mpjpe_mm()},
              {"mpjpe_mm", m.mpjpe_mm()},
              {"acc_error_mm", m.acc_error_mm()},
              {"vel_error_mm", m.vel_error_mm()}};
    // Per body by name when the sizes agree, else as the raw list (body_names order).
    if (m.body_error_mm_size() == spec->body_names_size()) {
      Json bodies = Json::object();
      for (int b = 0; b < m.body_error_mm_size(); ++b) bodies[spec->body_names(b)] = m.body_error_mm(b);
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
    if (frames) {
      auto it = frame_list_of.find(m.clip());
      Json list = it == frame_list_of.end() ? Json::array() : std::move(frame_lists[it->second].second);
      std::stable_sort(list.begin(), list.end(),
                       [](const Json& a, const Json& b) { return a["frame"].get<int>() < b["frame"].get<int>(); });
      clip["frames"] = std::move(list);
    }
    clip_list.push_back(std::move(clip));
  }
  json["clips"] = std::move(clip_list);
  // Frames make the file large: write it compact then.
  const std::string text = frames ? json.dump() : json.dump(2);
  if (absl::Status status = WriteFileAtomically(out, text + "\n"); !status.ok()) {
    return Fail(absl::StrCat("--out: ", status.message()));
  }
  std::printf("wrote %s: %s%s\n", out.c_str(), FormatBytes(text.size() + 1).c_str(),
              frames ? absl::StrCat(", ", num_frames, " frames").c_str() : "");
  return 0;
}

int Simulate(SimulationClient& client, const std::vector<std::string>& clips) {
  const int num_envs = absl::GetFlag(FLAGS_envs);
  const int steps = absl::GetFlag(FLAGS_steps);
  const bool random = absl::GetFlag(FLAGS_actions) == "random";
  v1::SessionConfig config;
  config.set_num_envs(num_envs);
  config.set_seed(absl::GetFlag(FLAGS_seed));
  config.set_part_layout(absl::GetFlag(FLAGS_part_layout));
  for (const std::string& clip : clips) config.add_motions(clip);

  auto session = client.OpenSession(config);
  if (!session.ok()) return Fail(session.status());
  SimulationStream& stream = **session;
  const int action_size = stream.spec().action_size();
  std::printf("session %s at %s: %d envs, %d clips, layout %s, obs %d, action %d\n",
              stream.opened().session_id().c_str(), client.server().c_str(), num_envs,
              stream.opened().clip_names_size(), stream.spec().part_layout().c_str(), stream.spec().obs_size(),
              action_size);
  std::fflush(stdout);

  std::vector<float> actions(static_cast<size_t>(num_envs) * action_size, 0.0f);
  std::mt19937_64 rng(absl::GetFlag(FLAGS_seed));
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::vector<float> reward;
  double reward_sum = 0;
  int64_t reward_count = 0, episodes = 0, truncated = 0;
  double stepping_seconds = 0;
  for (int step = 0; step < steps; ++step) {
    if (random) {
      for (float& a : actions) a = uniform(rng);
    }
    const auto start = std::chrono::steady_clock::now();
    if (absl::Status status = stream.Step(actions.data()); !status.ok()) return Fail(status);
    stepping_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const v1::StepResult& result = stream.result();
    if (absl::Status status = DecodeFloatTensor(result.reward(), "StepResult.reward", &reward); !status.ok()) {
      return Fail(status);
    }
    for (float r : reward) reward_sum += r;
    reward_count += static_cast<int64_t>(reward.size());
    if (result.done().dtype() != v1::UINT8 || result.truncated().dtype() != v1::UINT8) {
      return Fail("StepResult.done/truncated: not UINT8");
    }
    for (char d : result.done().data()) episodes += d != 0;
    for (char t : result.truncated().data()) truncated += t != 0;
  }
  const size_t request_bytes = stream.last_request_bytes();
  const size_t response_bytes = stream.last_response_bytes();
  if (absl::Status status = stream.Close(); !status.ok()) return Fail(status);

  const int64_t env_steps = int64_t{num_envs} * steps;
  std::printf("%d steps x %d envs (%s actions) in %.2f s: %.1f env steps/s, %.1f steps/s\n", steps, num_envs,
              random ? "random" : "zero", stepping_seconds,
              stepping_seconds > 0 ? env_steps / stepping_seconds : 0.0,
              stepping_seconds > 0 ? steps / stepping_seconds : 0.0);
  std::printf("mean reward %.4f, episodes ended %lld (%lld truncated)\n",
              reward_count > 0 ? reward_sum / reward_count : 0.0, static_cast<long long>(episodes),
              static_cast<long long>(truncated));
  std::printf("message sizes per step: request %s, response %s\n", FormatBytes(request_bytes).c_str(),
              FormatBytes(response_bytes).c_str());
  return 0;
}

int Main(int argc, char** argv) {
  absl::SetProgramUsageMessage(kUsage);
  // --help lists this file's flags (absl's default looks for <program name>.cc).
  absl::FlagsUsageConfig usage_config;
  usage_config.contains_help_flags = [](absl::string_view path) {
    return absl::EndsWith(path, "modskill_client_main.cc");
  };
  usage_config.contains_helpshort_flags = usage_config.contains_help_flags;
  usage_config.version_string = [] { return std::string("modskill-client 0.1.0\n"); };
  absl::SetFlagsUsageConfig(usage_config);
  std::vector<std::string> clips;
  if (std::string error; !PrescanFlags(argc, argv, &clips, &error)) return Usage(error);
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  if (clips.empty()) clips = absl::GetFlag(FLAGS_clip);  // e.g. from a --flagfile
  if (args.size() < 2) return Usage("no command given");
  const std::string command = args[1];
  const std::vector<std::string> operands(args.begin() + 2, args.end());

  static const char* const kCommands[] = {"describe", "motions", "stats", "add-motions", "rollout", "simulate"};
  if (std::find(std::begin(kCommands), std::end(kCommands), command) == std::end(kCommands)) {
    return Usage(absl::StrCat("unknown command '", command, "'"));
  }
  if (command == "add-motions") {
    if (operands.empty()) return Usage("add-motions: give at least one FILE");
  } else if (!operands.empty()) {
    return Usage(absl::StrCat(command, ": unexpected argument '", operands[0], "'"));
  }
  const double timeout = absl::GetFlag(FLAGS_timeout_s);
  if (!(timeout > 0) || timeout > 86400) return Usage("--timeout_s must be in (0, 86400]");
  // gRPC would quietly use port 443 for a bare host name.
  if (absl::GetFlag(FLAGS_server).find(':') == std::string::npos) {
    return Usage(absl::StrCat("--server: '", absl::GetFlag(FLAGS_server), "' has no port; give host:port"));
  }
  if (command == "rollout") {
    if (absl::GetFlag(FLAGS_checkpoint).empty()) return Usage("rollout: --checkpoint is required");
    if (absl::GetFlag(FLAGS_frames) && absl::GetFlag(FLAGS_out).empty()) {
      return Usage("rollout: --frames needs --out (frames go to the JSON file)");
    }
  }
  if (command == "simulate") {
    if (absl::GetFlag(FLAGS_envs) < 1) return Usage("--envs must be >= 1");
    if (absl::GetFlag(FLAGS_steps) < 1) return Usage("--steps must be >= 1");
    const std::string actions = absl::GetFlag(FLAGS_actions);
    if (actions != "zero" && actions != "random") {
      return Usage(absl::StrCat("--actions must be zero or random, not '", actions, "'"));
    }
  }

  auto client = Connect();
  if (!client.ok()) {
    if (client.status().code() == absl::StatusCode::kUnavailable) {
      return Fail(absl::StrCat(client.status().message(),
                               " (is modskill-server running there and reachable? a TLS server needs --tls_ca, "
                               "and --tls_server_name must match its certificate; a plain server needs no --tls_ca)"));
    }
    return Fail(client.status());
  }
  if (command == "describe") return Describe(**client);
  if (command == "motions") return Motions(**client);
  if (command == "stats") return Stats(**client);
  if (command == "add-motions") return AddMotions(**client, operands);
  if (command == "rollout") return Rollout(**client, clips);
  return Simulate(**client, clips);
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) { return modskill::Main(argc, argv); }
