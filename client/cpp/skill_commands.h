// modskill-client skills and compose (ModSkill's skill reuse, issue 13).
//
// skills: records a tracker's per-part z on clips (Rollout with record_skills) and writes
// DIR/skills.json: per clip and frame the z of every part, and a 2-D PCA of all of them (for
// tools/plot_skills.py's embedding plot, coloured by clip and part).
//
// compose: runs the base clip with some parts' z from the source clip (swapped, or interpolated
// over time), and the two clips plainly for comparison, and writes DIR/compose.json (metrics,
// the composition report, per frame the body positions, z and the composed parts' speed) and
// DIR/compose.html (the three rollouts in the viewer).
#ifndef MODSKILL_CLIENT_CPP_SKILL_COMMANDS_H_
#define MODSKILL_CLIENT_CPP_SKILL_COMMANDS_H_

#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

struct SkillOptions {
  std::string checkpoint;  // a local file, uploaded
  std::vector<std::string> clips;
  std::string out_dir;
  // compose only:
  std::string base, source;
  std::vector<std::string> parts;
  bool interpolate = false;
  int max_steps = 0;  // per clip; 0: the clip's length
};

// Both return the exit code.
int RecordSkills(SimulationClient& client, const SkillOptions& options);
int Compose(SimulationClient& client, const SkillOptions& options);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_SKILL_COMMANDS_H_
