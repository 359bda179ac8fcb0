// Simulation throughput against its physical limit (docs/DESIGN.md section 5).
//
// The limit: raw mj_step calls per second on one thread for the generated humanoid, driven
// through the same reference-tracking workload as the envs (PD targets = the reference's next
// frame, reset to a random reference state when it falls), divided by the substeps per control
// step. Then EnvBatch control steps/s at 64 and 256 envs with 1 and 2 threads, with the same
// open-loop reference actions. Repeats interleave the configurations and report medians.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "bench/median.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/env/reference_actions.h"
#include "server/core/util/data_paths.h"

ABSL_FLAG(int, repeats, 5, "measurements per configuration (median reported)");
ABSL_FLAG(double, seconds, 1.5, "seconds per measurement");
ABSL_FLAG(std::string, pd_mode, "position_implicit", "position_implicit or stable_pd");
ABSL_FLAG(int, substeps, 4, "physics substeps per 30 Hz control step");

namespace modskill {
namespace {

using Clock = std::chrono::steady_clock;

// mj_step calls per second, timing nothing but mj_step.
double RawStepRate(const HumanoidModel& humanoid, const MotionLibrary& motions, double seconds, uint64_t seed) {
  const mjModel* m = humanoid.model();
  mjData* d = mj_makeData(m);
  std::mt19937_64 rng(seed);
  HumanoidState state;
  state.Resize(humanoid.num_bodies(), humanoid.num_hinges());
  double stepping = 0;
  int64_t steps = 0;
  while (stepping < seconds) {
    const int c = std::uniform_int_distribution<int>(0, motions.size() - 1)(rng);
    const MotionClip& clip = motions.clip(c);
    int frame = std::uniform_int_distribution<int>(0, clip.num_frames - 2)(rng);
    SetSimulationToReference(humanoid, clip, frame, d);
    // One episode: follow the clip for up to its end, or 2 s, or until the pelvis drops.
    for (int k = 0; k < 60 && frame + 1 < clip.num_frames; ++k, ++frame) {
      for (int h = 0; h < humanoid.num_hinges(); ++h) d->ctrl[h] = clip.dof_pos[(frame + 1) * clip.num_hinges() + h];
      const auto start = Clock::now();
      for (int s = 0; s < humanoid.options().substeps; ++s) mj_step(m, d);
      stepping += std::chrono::duration<double>(Clock::now() - start).count();
      steps += humanoid.options().substeps;
      if (d->qpos[2] < 0.3) break;
    }
  }
  mj_deleteData(d);
  return steps / stepping;
}

double BatchStepRate(EnvBatch* batch, double seconds) {
  std::vector<float> actions(static_cast<size_t>(batch->num_envs()) * batch->spec().action_size);
  batch->Reset();
  double stepping = 0;
  int64_t env_steps = 0;
  while (stepping < seconds) {
    actions = ReferenceActions(*batch);
    const auto start = Clock::now();
    const absl::Status status = batch->Step(actions);
    stepping += std::chrono::duration<double>(Clock::now() - start).count();
    if (!status.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
      return 0;
    }
    env_steps += batch->num_envs();
  }
  return env_steps / stepping;
}

int Run() {
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return std::fprintf(stderr, "error: %s\n", std::string(spec.status().message()).c_str()), 1;
  auto library = MotionLibrary::LoadDefault(*spec);
  if (!library.ok()) return std::fprintf(stderr, "error: %s\n", std::string(library.status().message()).c_str()), 1;
  auto motions = std::make_shared<const MotionLibrary>(*std::move(library));
  auto pd_mode = ParsePdMode(absl::GetFlag(FLAGS_pd_mode));
  if (!pd_mode.ok()) return std::fprintf(stderr, "error: %s\n", std::string(pd_mode.status().message()).c_str()), 2;
  PhysicsOptions physics;
  physics.pd_mode = *pd_mode;
  physics.substeps = absl::GetFlag(FLAGS_substeps);
  auto humanoid = HumanoidModel::Create(*spec, physics);
  if (!humanoid.ok()) return std::fprintf(stderr, "error: %s\n", std::string(humanoid.status().message()).c_str()), 1;
  auto catalog = PartLayoutCatalog::LoadDefault(*spec);
  auto layout = catalog->Get(catalog->default_name());

  const int env_counts[] = {64, 256};
  const int thread_counts[] = {1, 2};
  std::vector<std::unique_ptr<EnvBatch>> batches;
  for (int envs : env_counts) {
    for (int threads : thread_counts) {
      EnvBatchConfig config;
      config.num_envs = envs;
      config.num_threads = threads;
      config.seed = 7;
      config.physics = physics;
      auto batch = EnvBatch::Create(config, *humanoid, *layout, motions);
      if (!batch.ok()) return std::fprintf(stderr, "error: %s\n", std::string(batch.status().message()).c_str()), 1;
      batches.push_back(*std::move(batch));
    }
  }
  const double seconds = absl::GetFlag(FLAGS_seconds);
  std::vector<double> raw;
  std::vector<std::vector<double>> rates(batches.size());
  for (int r = 0; r < absl::GetFlag(FLAGS_repeats); ++r) {
    raw.push_back(RawStepRate(**humanoid, *motions, seconds, 100 + r));
    for (size_t b = 0; b < batches.size(); ++b) rates[b].push_back(BatchStepRate(batches[b].get(), seconds));
  }
  const int substeps = physics.substeps;
  const double limit = Median(raw) / substeps;
  std::printf("pd %s, physics %.0f Hz, %d substeps per control step, %d repeats x %.1f s, medians\n",
              std::string(PdModeName(physics.pd_mode)).c_str(), 1.0 / physics.physics_dt(), substeps,
              absl::GetFlag(FLAGS_repeats), seconds);
  std::printf("raw mj_step: %.0f steps/s on one thread -> limit %.0f control steps/s per thread\n", Median(raw), limit);
  std::printf("%6s %8s %14s %16s %14s\n", "envs", "threads", "env steps/s", "per thread/limit", "vs 1 thread");
  size_t b = 0;
  for (int envs : env_counts) {
    double one_thread = 0;
    for (int threads : thread_counts) {
      const double rate = Median(rates[b++]);
      if (threads == 1) one_thread = rate;
      std::printf("%6d %8d %14.0f %16.3f %14.3f\n", envs, threads, rate, rate / threads / limit, rate / one_thread);
    }
  }
  return 0;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::Run();
}
