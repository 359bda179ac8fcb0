// modskill-client describe: the env spec of a part layout (sizes, control dt, layouts) and one
// line per body part.
#ifndef MODSKILL_CLIENT_CPP_DESCRIBE_COMMAND_H_
#define MODSKILL_CLIENT_CPP_DESCRIBE_COMMAND_H_

#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

// `part_layout`: empty for the server's default. Returns the exit code.
int Describe(SimulationClient& client, const std::string& part_layout);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_DESCRIBE_COMMAND_H_
