// modskill-client add-motions: uploads clip files to the server's library.
#ifndef MODSKILL_CLIENT_CPP_ADD_MOTIONS_COMMAND_H_
#define MODSKILL_CLIENT_CPP_ADD_MOTIONS_COMMAND_H_

#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

// `files`: .npz .bvh .txt .msclip paths, at least one. Returns the exit code.
int AddMotions(SimulationClient& client, const std::vector<std::string>& files);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_ADD_MOTIONS_COMMAND_H_
