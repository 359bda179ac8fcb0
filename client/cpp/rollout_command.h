// modskill-client rollout: evaluates a TorchScript policy on the server's clips, prints one line
// of metrics per clip and their means, and with --out writes them (per body, per part and, with
// --frames, the streamed body positions) as JSON; with --html writes the viewer page of the
// rollout beside its reference.
#ifndef MODSKILL_CLIENT_CPP_ROLLOUT_COMMAND_H_
#define MODSKILL_CLIENT_CPP_ROLLOUT_COMMAND_H_

#include <string>
#include <utility>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

struct RolloutOptions {
  // With `upload`, a local file whose bytes are sent; otherwise a path the server reads (made
  // absolute here).
  std::string checkpoint;
  bool upload = true;
  std::vector<std::string> clips;  // empty: every clip
  std::string out;                 // JSON file to write; empty: none
  bool frames = false;             // stream per-frame body positions into `out`
  std::string html;                // viewer page to write (the rollout beside its reference); empty: none
  // A motor-skill family's policy: its task parameters a by name (--param gravity=6); the server
  // runs the rest at their ranges' middles and refuses a value outside the trained range.
  std::vector<std::pair<std::string, double>> family_params;
};

// Returns the exit code.
int Rollout(SimulationClient& client, const RolloutOptions& options);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_ROLLOUT_COMMAND_H_
