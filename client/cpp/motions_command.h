// modskill-client motions: the server's motion library, one line per clip.
#ifndef MODSKILL_CLIENT_CPP_MOTIONS_COMMAND_H_
#define MODSKILL_CLIENT_CPP_MOTIONS_COMMAND_H_

#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

// Returns the exit code.
int Motions(SimulationClient& client);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_MOTIONS_COMMAND_H_
