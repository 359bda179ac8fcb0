// modskill-client stats: server totals, live sessions, and per session its most sampled clips
// and generation figures.
#ifndef MODSKILL_CLIENT_CPP_STATS_COMMAND_H_
#define MODSKILL_CLIENT_CPP_STATS_COMMAND_H_

#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

// Returns the exit code.
int Stats(SimulationClient& client);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_STATS_COMMAND_H_
