#include "client/cpp/describe_command.h"

#include <algorithm>
#include <cstdio>

#include "absl/strings/str_join.h"
#include "client/cpp/cli_output.h"

namespace modskill::cli {

int Describe(SimulationClient& client, const std::string& part_layout) {
  auto spec = client.Describe(part_layout);
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
  if (const v1::PhysicsSettings& physics = spec->physics(); physics.physics_dt() > 0) {
    std::printf("  physics       %.6g s (%.4g Hz), %s servos, gains x %g%s\n", physics.physics_dt(),
                1.0 / physics.physics_dt(), physics.pd_mode().c_str(), physics.pd_gain_scale(),
                physics.damp_to_reference_rate() ? ", damped toward the reference's rate" : "");
  }
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
  // Older servers list no tasks.
  if (spec->tasks_size() > 0) std::printf("tasks (SessionConfig.task; goal floats after the self features):\n");
  for (const v1::TaskInfo& task : spec->tasks()) {
    std::printf("  %-12s goal %3d  reward %s\n      %s\n", task.name().c_str(), task.goal_size(),
                absl::StrJoin(task.reward_terms(), " + ").c_str(), task.description().c_str());
    if (task.tracked_bodies_size() > 0) {
      std::printf("      tracked bodies: %s\n", absl::StrJoin(task.tracked_bodies(), " ").c_str());
    }
  }
  return 0;
}

}  // namespace modskill::cli
