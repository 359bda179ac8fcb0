// modskill-client family: a motor-skill family's policy.pt (modskill-learner --family) at task
// parameters a, through the server's QueryFamily: the trained ranges, the elites nearest a and a
// summary of P(a), the parameterization network's edited motion (per frame: the hinges'
// displacements and the time warp); with --out the whole answer, P(a) included, as JSON.
#ifndef MODSKILL_CLIENT_CPP_FAMILY_COMMAND_H_
#define MODSKILL_CLIENT_CPP_FAMILY_COMMAND_H_

#include <string>
#include <utility>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

struct FamilyQueryOptions {
  std::string checkpoint;  // as RolloutOptions: a local file to upload, or a path the server reads
  bool upload = true;
  std::vector<std::pair<std::string, double>> params;  // --param name=value
  int nearest_elites = 0;                              // 0: the server's default (5)
  std::string out;                                     // JSON file; empty: none
};

// Returns the exit code.
int QueryFamily(SimulationClient& client, const FamilyQueryOptions& options);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_FAMILY_COMMAND_H_
