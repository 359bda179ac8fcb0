#include "client/cpp/stats_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "client/cpp/cli_output.h"

namespace modskill::cli {

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

}  // namespace modskill::cli
