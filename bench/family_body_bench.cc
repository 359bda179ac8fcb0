// What body proportions cost a family session (issue 14: "each env may need its own mjModel:
// keep the no-allocation-per-step rule and measure the cost"). Side by side, interleaved, one
// thread: env steps/s of a family session over gravity alone, and over leg_scale and arm_scale
// (every episode at other proportions: a model copied into the env's own, the clip scaled to its
// skeleton, and a compile on a cache miss: leg_scale alone fills its 41 models within the first
// repeat, both scales' 1,681 pairs take far longer than this bench); then the time of one compile
// of a scaled model. The
// actions are the open-loop clip at its own pace (zero displacement, tau 0).
#include <chrono>
#include <cstdio>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "bench/median.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/family_body_models.h"
#include "server/core/motion/motion_library.h"

ABSL_FLAG(int, repeats, 5, "measurements per configuration (median reported)");
ABSL_FLAG(double, seconds, 2.0, "seconds per measurement");
ABSL_FLAG(int, envs, 64, "envs in the session");
ABSL_FLAG(std::string, clip, "deepmimic_walk", "the family's clip");

namespace modskill {
namespace {

using Clock = std::chrono::steady_clock;

struct Rate {
  double steps_per_s = 0;
  double episodes_per_s = 0;
};

Rate Measure(EnvBatch& batch, double seconds) {
  std::vector<float> actions(static_cast<size_t>(batch.num_envs()) * batch.spec().action_size, 0.f);
  int64_t steps = 0, episodes = 0;
  const auto start = Clock::now();
  double elapsed = 0;
  while (elapsed < seconds) {
    if (!batch.Step(actions).ok()) std::abort();
    steps += batch.num_envs();
    for (int i = 0; i < batch.num_envs(); ++i) episodes += batch.buffers().done[i];
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  }
  return {steps / elapsed, episodes / elapsed};
}

int Main() {
  auto library = MotionLibrary::LoadDefault(HumanoidSpec::LoadDefault().value());
  if (!library.ok()) return std::printf("error: %s\n", std::string(library.status().message()).c_str()), 1;
  auto one = library->Subset({absl::GetFlag(FLAGS_clip)});
  if (!one.ok()) return std::printf("error: %s\n", std::string(one.status().message()).c_str()), 1;
  auto motions = std::make_shared<const MotionLibrary>(*std::move(one));
  const std::vector<std::pair<const char*, std::vector<ParamRange>>> families = {
      {"gravity 4-14", {{"gravity", 4, 14}}},
      {"gravity, leg_scale 0.8-1.2 (41 models)", {{"gravity", 4, 14}, {"leg_scale", 0.8, 1.2}}},
      {"gravity, leg_scale, arm_scale 0.8-1.2 (1,681)", {{"gravity", 4, 14}, {"leg_scale", 0.8, 1.2}, {"arm_scale", 0.8, 1.2}}}};
  std::vector<std::unique_ptr<EnvBatch>> batches;
  for (const auto& [name, ranges] : families) {
    EnvBatchConfig config;
    config.num_envs = absl::GetFlag(FLAGS_envs);
    config.num_threads = 1;
    config.env.action.mode = ActionMode::kResidual;
    config.env.termination_distance = 1.0;
    config.env.family = ranges;
    auto batch = EnvBatch::Create(config, motions);
    if (!batch.ok()) return std::printf("error: %s\n", std::string(batch.status().message()).c_str()), 1;
    (*batch)->Reset();
    batches.push_back(*std::move(batch));
  }
  std::vector<std::vector<Rate>> rates(batches.size());
  for (int r = 0; r < absl::GetFlag(FLAGS_repeats); ++r) {
    for (size_t b = 0; b < batches.size(); ++b) rates[b].push_back(Measure(*batches[b], absl::GetFlag(FLAGS_seconds)));
  }
  std::printf("family sessions on %s, %d envs, 1 thread, open-loop actions, %d repeats x %.1f s, medians\n",
              absl::GetFlag(FLAGS_clip).c_str(), absl::GetFlag(FLAGS_envs), absl::GetFlag(FLAGS_repeats),
              absl::GetFlag(FLAGS_seconds));
  std::vector<double> base;
  for (size_t b = 0; b < batches.size(); ++b) {
    std::vector<double> steps, episodes, ratio;
    for (size_t r = 0; r < rates[b].size(); ++r) {
      steps.push_back(rates[b][r].steps_per_s);
      episodes.push_back(rates[b][r].episodes_per_s);
      ratio.push_back(rates[b][r].steps_per_s / rates[0][r].steps_per_s);
    }
    std::printf("  %-48s %8.0f env steps/s  %6.1f episodes/s  %.3f x gravity alone\n", families[b].first, Median(steps),
                Median(episodes), Median(ratio));
  }
  // One compile of a scaled humanoid (a cache miss), timed on fresh value pairs.
  FamilyBodyModels models(std::shared_ptr<const HumanoidModel>(&batches[0]->humanoid(), [](const HumanoidModel*) {}));
  std::vector<double> compile_ms;
  for (int k = 0; k < 9; ++k) {
    const auto start = Clock::now();
    if (!models.Get(0.81 + 0.04 * k, 1.0).ok()) std::abort();
    compile_ms.push_back(1000 * std::chrono::duration<double>(Clock::now() - start).count());
  }
  std::printf("  one scaled model compiled (a cache miss): %.1f ms (median of 9); its numbers: %.0f KB\n",
              Median(compile_ms), batches[0]->humanoid().model()->nbuffer / 1024.0);
  return 0;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::Main();
}
