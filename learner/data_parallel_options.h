// How a learner joins a data-parallel group (data_parallel.h): its rank among world_size learners
// and rank 0's rendezvous address. World size 1, the default, is a learner on its own.
#ifndef MODSKILL_LEARNER_DATA_PARALLEL_OPTIONS_H_
#define MODSKILL_LEARNER_DATA_PARALLEL_OPTIONS_H_

#include <string>

#include "absl/status/status.h"

namespace modskill::learner {

struct DataParallelOptions {
  int world_size = 1;
  int rank = 0;
  std::string rendezvous;            // host:port; rank 0 listens on the port, every rank connects
  double rendezvous_timeout_s = 60;  // joining, and each startup exchange once the servers answer
  // One collective. Ranks meet in collectives once per minibatch and wait there for the slowest
  // rank's collection, which may wait up to --server_timeout_s (120 s) for its servers: longer.
  double collective_timeout_s = 300;
};

// INVALID_ARGUMENT naming the flag (--world_size, --rank, --rendezvous, the timeouts) unless
// `options` can form a group: world_size >= 1, rank in [0, world_size), and with world_size > 1 a
// rendezvous host:port with a port in [1, 65535].
absl::Status ValidateDataParallelOptions(const DataParallelOptions& options);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_DATA_PARALLEL_OPTIONS_H_
