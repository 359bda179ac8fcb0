// The addresses behind a DNS name, from the system resolver (getaddrinfo), within a time limit.
// The learner keeps one stateful session per simulation server, so it needs every address a
// name resolves to, each on its own channel; gRPC C++ resolves names inside a channel and does not
// hand the addresses out through its public API, so server discovery asks the system resolver.
#ifndef MODSKILL_LEARNER_ADDRESS_RESOLVER_H_
#define MODSKILL_LEARNER_ADDRESS_RESOLVER_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace modskill::learner {

// "ip:port" (IPv6 as "[ip]:port") for every TCP address of `host`, sorted, without repeats. Where
// the name has IPv4 addresses only those are returned: a dual-stack name (localhost, a dual-stack
// Kubernetes service) lists each server once per family, and two sessions on one server would
// halve its share. NOT_FOUND when the name resolves to nothing, DEADLINE_EXCEEDED when the
// resolver does not answer within `timeout` (its thread is left to finish on its own), UNAVAILABLE
// for other resolver errors; every message names the host.
absl::StatusOr<std::vector<std::string>> ResolveTcpAddresses(const std::string& host, int port,
                                                             absl::Duration timeout);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_ADDRESS_RESOLVER_H_
