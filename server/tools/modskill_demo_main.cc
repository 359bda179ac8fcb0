// modskill-demo: loads the shipped motion library, steps a batch of tracking envs and prints
// throughput and what the envs saw. The main job until the learner exists.
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "server/core/env/env_batch.h"
#include "server/core/util/data_paths.h"

ABSL_FLAG(int, envs, 64, "number of environments");
ABSL_FLAG(int, threads, 2, "worker threads");
ABSL_FLAG(int, steps, 300, "control steps (30 Hz) to run");
ABSL_FLAG(std::string, motions, "", "directory of .msclip files (default: the shipped library)");
ABSL_FLAG(std::string, actions, "zero", "zero (hold the PD offset) or random (uniform in [-1, 1])");
ABSL_FLAG(std::string, part_layout, "5part", "body-part layout: 5part, 3part, 2part, 1part");
ABSL_FLAG(std::string, pd_mode, "position_implicit", "position_implicit or stable_pd");
ABSL_FLAG(uint64_t, seed, 1, "random seed");

namespace modskill {
namespace {

// What the batch is: sizes, parts and physics.
void PrintBatch(EnvBatch& envs) {
  const EnvSpec& env_spec = envs.spec();
  std::printf("envs %d, threads %d, obs %d (self %d + task %d), actions %d, amp obs %d, parts %d (%s), "
              "physics %.0f Hz x %d substeps, pd %s\n",
              envs.num_envs(), envs.num_threads(), env_spec.obs_size, env_spec.self_obs_size, env_spec.task_obs_size,
              env_spec.action_size, env_spec.amp_obs_size, env_spec.layout.num_parts(), env_spec.layout.name.c_str(),
              1.0 / envs.humanoid().options().physics_dt(), envs.humanoid().options().substeps,
              std::string(PdModeName(envs.humanoid().options().pd_mode)).c_str());
}

// Steps the batch with zero or random actions and prints throughput, mean reward (per term) and
// episode ends. Returns the exit code.
int StepAndReport(EnvBatch& envs, const std::string& actions_mode, uint64_t seed, int steps) {
  const EnvSpec& env_spec = envs.spec();
  envs.Reset();
  std::vector<float> actions(static_cast<size_t>(envs.num_envs()) * env_spec.action_size, 0.f);
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::uniform_real_distribution<float> uniform(-1.f, 1.f);
  double reward_sum = 0, terms_sum[kNumRewardTerms] = {};
  int64_t episodes = 0, terminations = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s) {
    if (actions_mode == "random") {
      for (float& a : actions) a = uniform(rng);
    }
    if (auto status = envs.Step(actions); !status.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
      return 1;
    }
    const BatchBuffers& out = envs.buffers();
    for (int i = 0; i < envs.num_envs(); ++i) {
      reward_sum += out.reward[i];
      for (int t = 0; t < kNumRewardTerms; ++t) terms_sum[t] += out.reward_terms[i * kNumRewardTerms + t];
      if (out.done[i]) {
        ++episodes;
        if (!out.truncated[i]) ++terminations;
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double env_steps = static_cast<double>(steps) * envs.num_envs();
  std::printf("%d steps x %d envs in %.2f s: %.0f env steps/s (%.1f x real time per env)\n", steps, envs.num_envs(),
              seconds, env_steps / seconds, env_steps / seconds * env_spec.control_dt / envs.num_envs());
  std::printf("mean reward %.4f [", reward_sum / env_steps);
  for (int t = 0; t < kNumRewardTerms; ++t) std::printf("%s%s %.4f", t ? ", " : "", RewardTermName(t), terms_sum[t] / env_steps);
  std::printf("]\nepisodes ended %lld (terminated %lld), physics resets %lld\n", static_cast<long long>(episodes),
              static_cast<long long>(terminations), static_cast<long long>(envs.physics_resets()));
  return 0;
}

int Main() {
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(spec.status().message()).c_str());
    return 1;
  }
  const std::string motion_dir = absl::GetFlag(FLAGS_motions).empty() ? DataPath("motions") : absl::GetFlag(FLAGS_motions);
  auto library = MotionLibrary::LoadDirectory(motion_dir, *spec);
  if (!library.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(library.status().message()).c_str());
    return 1;
  }
  auto pd_mode = ParsePdMode(absl::GetFlag(FLAGS_pd_mode));
  if (!pd_mode.ok()) {
    std::fprintf(stderr, "error: --%s\n", std::string(pd_mode.status().message()).c_str());
    return 2;
  }
  const std::string actions_mode = absl::GetFlag(FLAGS_actions);
  if (actions_mode != "zero" && actions_mode != "random") {
    std::fprintf(stderr, "error: --actions must be zero or random, not '%s'\n", actions_mode.c_str());
    return 2;
  }
  std::printf("motion library %s: %d clips, %.1f s\n", motion_dir.c_str(), library->size(), library->TotalDuration());
  EnvBatchConfig config;
  config.num_envs = absl::GetFlag(FLAGS_envs);
  config.num_threads = absl::GetFlag(FLAGS_threads);
  config.seed = absl::GetFlag(FLAGS_seed);
  config.part_layout = absl::GetFlag(FLAGS_part_layout);
  config.physics.pd_mode = *pd_mode;
  auto batch = EnvBatch::Create(config, std::make_shared<const MotionLibrary>(*std::move(library)));
  if (!batch.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(batch.status().message()).c_str());
    return 2;
  }
  PrintBatch(**batch);
  return StepAndReport(**batch, actions_mode, config.seed, absl::GetFlag(FLAGS_steps));
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("steps a batch of humanoid tracking envs on the shipped motions");
  absl::ParseCommandLine(argc, argv);
  return modskill::Main();
}
