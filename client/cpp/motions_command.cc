#include "client/cpp/motions_command.h"

#include <algorithm>
#include <cstdio>
#include "client/cpp/cli_output.h"

namespace modskill::cli {

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

}  // namespace modskill::cli
