// Which PD keeps a reference pose better (issue: "stable PD, or position actuators with
// implicit damping: measure which keeps a reference pose better and pick it").
//
// For each PD mode and substep count: put the humanoid in reference poses sampled from the
// shipped clips and hold PD targets at that pose for one second (30 control steps).
//   hanging:  pelvis welded in the air, so only the PD fights gravity and inertia;
//   standing: free root on the floor from the first frame of the walk clips.
// Reports the joint angle error (deg) and the body position error relative to the pelvis (mm)
// after one second, the cost per control step, and whether anything diverged.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "server/core/env/humanoid_state.h"
#include "server/core/motion/motion_library.h"
#include "server/core/sim/pd_controller.h"

ABSL_FLAG(int, poses, 40, "hanging reference poses sampled across the library");

namespace modskill {
namespace {

struct HoldResult {
  double joint_error_deg = 0;   // mean over poses of mean |q - q_ref|
  double body_error_mm = 0;     // mean over poses of mean |(p_b - p_root) - (ref)|
  double worst_body_error_mm = 0;
  double micros_per_step = 0;
  int diverged = 0;
};

HoldResult Hold(const HumanoidModel& humanoid, const MotionLibrary& motions, const std::vector<std::pair<int, int>>& poses) {
  HoldResult result;
  const mjModel* m = humanoid.model();
  mjData* d = mj_makeData(m);
  PdController pd(humanoid);
  HumanoidState sim, ref;
  sim.Resize(humanoid.num_bodies(), humanoid.num_hinges());
  ref.Resize(humanoid.num_bodies(), humanoid.num_hinges());
  std::vector<double> targets(humanoid.num_hinges());
  double seconds = 0;
  int steps = 0;
  for (const auto& [clip_id, frame] : poses) {
    const MotionClip& clip = motions.clip(clip_id);
    SetSimulationToReference(humanoid, clip, frame, d);
    mju_zero(d->qvel, m->nv);  // hold a still pose
    for (int h = 0; h < humanoid.num_hinges(); ++h) {
      // The action range covers the joint range, so every target is reachable by an action.
      targets[h] = std::clamp(clip.dof_pos[frame * clip.num_hinges() + h], humanoid.model()->jnt_range[2 * (h + (humanoid.options().fixed_root ? 0 : 1))],
                              humanoid.model()->jnt_range[2 * (h + (humanoid.options().fixed_root ? 0 : 1)) + 1]);
    }
    bool diverged = false;
    const auto start = std::chrono::steady_clock::now();
    for (int s = 0; s < 30 && !diverged; ++s) {
      pd.Step(targets.data(), d);
      for (int i = 0; i < m->nv; ++i) diverged |= !std::isfinite(d->qvel[i]) || std::abs(d->qvel[i]) > 1e3;
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    steps += 30;
    if (diverged) {
      ++result.diverged;
      continue;
    }
    mj_forward(m, d);
    ReadSimulatedState(humanoid, d, &sim);
    double joint = 0, body = 0;
    for (int h = 0; h < humanoid.num_hinges(); ++h) joint += std::abs(WrapAngle(sim.dof_pos[h] - targets[h]));
    // Reference body positions for the clamped targets: FK of the targets from the sim's root.
    std::vector<Quat> rot(humanoid.num_bodies());
    std::vector<Vec3> pos(humanoid.num_bodies());
    rot[0] = sim.body_rot[0];
    pos[0] = sim.body_pos[0];
    for (int b = 1; b < humanoid.num_bodies(); ++b) {
      const int p = humanoid.spec().body(b).parent;
      const double* a = &targets[3 * (b - 1)];
      rot[b] = rot[p] * HingeRotation(a[0], a[1], a[2]);
      pos[b] = pos[p] + rot[p] * humanoid.spec().body(b).offset;
      body += (sim.body_pos[b] - pos[b]).norm();
    }
    joint /= humanoid.num_hinges();
    body /= humanoid.num_bodies() - 1;
    result.joint_error_deg += joint * 180.0 / M_PI / poses.size();
    result.body_error_mm += body * 1000.0 / poses.size();
    result.worst_body_error_mm = std::max(result.worst_body_error_mm, body * 1000.0);
  }
  result.micros_per_step = 1e6 * seconds / steps;
  mj_deleteData(d);
  return result;
}

int Run() {
  auto spec = HumanoidSpec::LoadDefault();
  auto library = MotionLibrary::LoadDefault(*spec);
  if (!spec.ok() || !library.ok()) return std::fprintf(stderr, "error: cannot load the default data\n"), 1;
  std::vector<std::pair<int, int>> hanging;
  const int count = absl::GetFlag(FLAGS_poses);
  for (int k = 0; k < count; ++k) {
    const int c = k % library->size();
    const MotionClip& clip = library->clip(c);
    hanging.emplace_back(c, (k * 7919) % (clip.num_frames - 1));
  }
  std::vector<std::pair<int, int>> standing;
  for (const char* name : {"deepmimic_walk", "cmu_02_01", "deepmimic_punch", "deepmimic_dance_a"}) {
    if (library->Find(name) >= 0) standing.emplace_back(library->Find(name), 0);
  }
  std::printf("hold a reference pose for 1 s (30 control steps); %d hanging poses, %d standing poses\n",
              static_cast<int>(hanging.size()), static_cast<int>(standing.size()));
  std::printf("%-18s %8s %6s | %12s %12s %12s | %12s %12s | %10s\n", "pd", "physics", "subst", "hang deg", "hang mm",
              "hang worst", "stand mm", "stand worst", "us/step");
  for (PdMode mode : {PdMode::kPositionImplicitDamping, PdMode::kStablePd}) {
    for (int substeps : {2, 4, 8}) {
      PhysicsOptions options;
      options.pd_mode = mode;
      options.substeps = substeps;
      PhysicsOptions hanging_options = options;
      hanging_options.fixed_root = true;
      hanging_options.fixed_root_height = 2.5;  // no floor contact
      auto fixed = HumanoidModel::Create(*spec, hanging_options);
      auto free = HumanoidModel::Create(*spec, options);
      if (!fixed.ok() || !free.ok()) return std::fprintf(stderr, "error: model does not compile\n"), 1;
      const HoldResult hang = Hold(**fixed, *library, hanging);
      const HoldResult stand = Hold(**free, *library, standing);
      std::printf("%-18s %6.0fHz %6d | %12.2f %12.1f %12.1f | %12.1f %12.1f | %10.0f%s\n",
                  std::string(PdModeName(mode)).c_str(), 1.0 / options.physics_dt(), substeps, hang.joint_error_deg,
                  hang.body_error_mm, hang.worst_body_error_mm, stand.body_error_mm, stand.worst_body_error_mm,
                  stand.micros_per_step, hang.diverged + stand.diverged ? "  DIVERGED" : "");
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
