// Where an mj_step of the humanoid spends its time, and what MuJoCo's solver settings buy.
//
// Drives copies of the generated humanoid through the reference-tracking workload of
// sim_throughput_bench (PD targets = the reference's next frame, reset to a random reference
// state when the pelvis drops) with MuJoCo's stage timers on, then repeats the same episodes
// (same seeds) under solver variants, interleaved, medians reported. Beside each variant's speed
// it reports how far its trajectories drift from the default's after one control second, so a
// cheaper setting can be judged by what it changes, not only by what it saves.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "bench/median.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/env/reference_actions.h"
#include "server/core/util/data_paths.h"

ABSL_FLAG(int, repeats, 5, "measurements per variant (median reported)");
ABSL_FLAG(int, episodes, 60, "episodes per measurement (each up to 30 control steps)");

namespace modskill {
namespace {

using Clock = std::chrono::steady_clock;

mjtNum NowMicroseconds() {
  return std::chrono::duration<double, std::micro>(Clock::now().time_since_epoch()).count();
}

struct Variant {
  std::string name;
  std::function<void(mjModel*)> apply;
};

struct Measurement {
  double steps_per_s = 0;
  std::vector<double> stage_us;    // mean µs per mj_step per timer
  std::vector<double> final_qpos;  // each episode's qpos after its last step, concatenated
  double mean_iterations = 0;      // solver iterations per mj_step
};

// Runs `episodes` reference-tracking episodes from seed-determined clips and frames.
Measurement RunEpisodes(const HumanoidModel& humanoid, const MotionLibrary& motions, const mjModel* m, int episodes,
                        uint64_t seed) {
  mjData* d = mj_makeData(m);
  std::mt19937_64 rng(seed);
  Measurement result;
  std::vector<double> timer_sum(mjNTIMER, 0);
  double stepping = 0, iterations = 0;
  int64_t steps = 0;
  for (int e = 0; e < episodes; ++e) {
    const int c = std::uniform_int_distribution<int>(0, motions.size() - 1)(rng);
    const MotionClip& clip = motions.clip(c);
    int frame = std::uniform_int_distribution<int>(0, std::max(0, clip.num_frames - 32))(rng);
    mj_resetData(m, d);
    SetSimulationToReference(humanoid, clip, frame, d);
    for (int k = 0; k < 30 && frame + 1 < clip.num_frames; ++k, ++frame) {
      for (int h = 0; h < humanoid.num_hinges(); ++h) d->ctrl[h] = clip.dof_pos[(frame + 1) * clip.num_hinges() + h];
      const auto start = Clock::now();
      for (int s = 0; s < humanoid.options().substeps; ++s) {
        mj_step(m, d);
        iterations += d->solver_iter;
      }
      stepping += std::chrono::duration<double>(Clock::now() - start).count();
      steps += humanoid.options().substeps;
    }
    for (int i = 0; i < m->nq; ++i) result.final_qpos.push_back(d->qpos[i]);
    for (int t = 0; t < mjNTIMER; ++t) {
      timer_sum[t] += d->timer[t].duration;
      d->timer[t].duration = 0;
      d->timer[t].number = 0;
    }
  }
  mj_deleteData(d);
  result.steps_per_s = steps / stepping;
  for (double sum : timer_sum) result.stage_us.push_back(sum / steps);
  result.mean_iterations = iterations / steps;
  return result;
}

// Mean distance (m) between the pelvis positions two variants reach at each episode's end.
double PelvisDrift(const std::vector<double>& a, const std::vector<double>& b, int nq) {
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i + 2 < a.size(); i += nq, ++n) {
    sum += std::sqrt((a[i] - b[i]) * (a[i] - b[i]) + (a[i + 1] - b[i + 1]) * (a[i + 1] - b[i + 1]) +
                     (a[i + 2] - b[i + 2]) * (a[i + 2] - b[i + 2]));
  }
  return n ? sum / n : 0;
}

int Run() {
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return std::fprintf(stderr, "error: %s\n", std::string(spec.status().message()).c_str()), 1;
  auto library = MotionLibrary::LoadDefault(*spec);
  if (!library.ok()) return std::fprintf(stderr, "error: %s\n", std::string(library.status().message()).c_str()), 1;
  auto humanoid = HumanoidModel::Create(*spec, PhysicsOptions{});
  if (!humanoid.ok()) return std::fprintf(stderr, "error: %s\n", std::string(humanoid.status().message()).c_str()), 1;
  mjcb_time = NowMicroseconds;

  const std::vector<Variant> variants = {
      {"default", [](mjModel*) {}},
      {"iterations 20", [](mjModel* m) { m->opt.iterations = 20; }},
      {"tolerance 1e-6", [](mjModel* m) { m->opt.tolerance = 1e-6; }},
      {"jacobian dense", [](mjModel* m) { m->opt.jacobian = mjJAC_DENSE; }},
      {"solver CG", [](mjModel* m) { m->opt.solver = mjSOL_CG; }},
      {"solver PGS", [](mjModel* m) { m->opt.solver = mjSOL_PGS; }},
      {"cone elliptic", [](mjModel* m) { m->opt.cone = mjCONE_ELLIPTIC; }},
      {"no warmstart", [](mjModel* m) { m->opt.disableflags |= mjDSBL_WARMSTART; }},
      {"no self-collision", [](mjModel* m) {
         for (int g = 1; g < m->ngeom; ++g) m->geom_conaffinity[g] = 0;
       }},
  };
  std::vector<mjModel*> models;
  for (const Variant& variant : variants) {
    mjModel* copy = mj_copyModel(nullptr, (*humanoid)->model());
    variant.apply(copy);
    models.push_back(copy);
  }
  const int repeats = absl::GetFlag(FLAGS_repeats), episodes = absl::GetFlag(FLAGS_episodes);
  std::vector<std::vector<Measurement>> runs(variants.size());
  for (int r = 0; r < repeats; ++r) {
    for (size_t v = 0; v < variants.size(); ++v) {
      runs[v].push_back(RunEpisodes(**humanoid, *library, models[v], episodes, 100 + r));
    }
  }
  const int nq = models[0]->nq;
  std::printf("%d repeats x %d episodes of up to 30 control steps, %d substeps each; medians\n", repeats, episodes,
              (*humanoid)->options().substeps);
  std::printf("%-18s %10s %8s %10s %9s %9s %9s %9s %9s %9s\n", "variant", "mj_step/s", "vs def", "iters/step",
              "drift mm", "pos us", "vel us", "act us", "acc us", "con us");
  std::vector<double> default_rates;
  for (const Measurement& run : runs[0]) default_rates.push_back(run.steps_per_s);
  for (size_t v = 0; v < variants.size(); ++v) {
    std::vector<double> rates, ratios, drift, iters;
    std::vector<std::vector<double>> stage(mjNTIMER);
    for (int r = 0; r < repeats; ++r) {
      rates.push_back(runs[v][r].steps_per_s);
      ratios.push_back(runs[v][r].steps_per_s / runs[0][r].steps_per_s);
      drift.push_back(1000 * PelvisDrift(runs[v][r].final_qpos, runs[0][r].final_qpos, nq));
      iters.push_back(runs[v][r].mean_iterations);
      for (int t = 0; t < mjNTIMER; ++t) stage[t].push_back(runs[v][r].stage_us[t]);
    }
    std::printf("%-18s %10.0f %8.3f %10.2f %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f\n", variants[v].name.c_str(),
                Median(rates), Median(ratios), Median(iters), Median(drift), Median(stage[mjTIMER_POSITION]),
                Median(stage[mjTIMER_VELOCITY]), Median(stage[mjTIMER_ACTUATION]),
                Median(stage[mjTIMER_ACCELERATION]), Median(stage[mjTIMER_CONSTRAINT]));
    if (v == 0) {
      std::printf("  default's position stage: kinematics %.1f, inertia %.1f, collision %.1f, make %.1f, project %.1f us\n",
                  Median(stage[mjTIMER_POS_KINEMATICS]), Median(stage[mjTIMER_POS_INERTIA]),
                  Median(stage[mjTIMER_POS_COLLISION]), Median(stage[mjTIMER_POS_MAKE]),
                  Median(stage[mjTIMER_POS_PROJECT]));
    }
  }
  for (mjModel* m : models) mj_deleteModel(m);
  return 0;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::Run();
}
