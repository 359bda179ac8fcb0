// modskill-client simulate: opens a session, steps it with zero or random actions and reports env
// steps per second, the mean reward, episode ends and message sizes.
#ifndef MODSKILL_CLIENT_CPP_SIMULATE_COMMAND_H_
#define MODSKILL_CLIENT_CPP_SIMULATE_COMMAND_H_

#include <cstdint>
#include <string>
#include <vector>

#include "client/cpp/simulation_client.h"

namespace modskill::cli {

struct SimulateOptions {
  int num_envs = 16;
  int steps = 100;
  bool random_actions = false;  // uniform in [-1, 1]; false: zero actions
  uint64_t seed = 1;            // of the session and of the random actions
  std::string part_layout;      // empty: the server's default
  std::vector<std::string> clips;  // empty: every clip
};

// Returns the exit code.
int Simulate(SimulationClient& client, const SimulateOptions& options);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_SIMULATE_COMMAND_H_
