#include "client/cpp/add_motions_command.h"

#include <cstdio>

#include "absl/strings/str_cat.h"
#include "client/cpp/cli_output.h"

namespace modskill::cli {

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

}  // namespace modskill::cli
