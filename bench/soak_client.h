// The clients of soak_bench: each opens Simulate sessions, steps them for random lengths, dies
// abruptly, sends malformed requests and reconnects, and books every answer in a shared Tally.
#ifndef MODSKILL_BENCH_SOAK_CLIENT_H_
#define MODSKILL_BENCH_SOAK_CLIENT_H_

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/strings/str_cat.h"

namespace modskill {

// What the clients did.
struct Tally {
  std::mutex mutex;
  std::map<std::string, std::map<std::string, int64_t>> bad_by_kind;  // kind -> status code -> count
  std::vector<std::string> findings;                                  // first few, printed at the end
  int64_t findings_total = 0;
  std::atomic<int64_t> sessions_opened{0}, sessions_refused{0}, sessions_closed{0}, sessions_killed{0};
  std::atomic<int64_t> steps{0}, env_steps{0}, bad_requests{0}, good_calls{0}, reconnects{0};

  void Finding(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    ++findings_total;
    if (findings.size() < 20) findings.push_back(what);
  }
  // A malformed request's answer: any clean refusal is fine; OK, UNKNOWN, INTERNAL or a deadline
  // is a finding.
  void Bad(const std::string& kind, const grpc::Status& status) {
    ++bad_requests;
    const grpc::StatusCode code = status.error_code();
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++bad_by_kind[kind][CodeName(code)];
    }
    if (code == grpc::OK || code == grpc::UNKNOWN || code == grpc::INTERNAL || code == grpc::DEADLINE_EXCEEDED) {
      Finding(absl::StrCat(kind, ": ", CodeName(code), " ", status.error_message().substr(0, 200)));
    }
  }
  // A well-formed request that failed.
  void Good(const std::string& kind, const grpc::Status& status) {
    ++good_calls;
    if (!status.ok() && status.error_code() != grpc::RESOURCE_EXHAUSTED) {
      Finding(absl::StrCat(kind, " (well-formed): ", CodeName(status.error_code()), " ",
                           status.error_message().substr(0, 200)));
    }
  }
  static std::string CodeName(grpc::StatusCode code) {
    static const char* kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                   "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                   "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED",
                                   "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
    const int index = static_cast<int>(code);
    return index >= 0 && index < 17 ? kNames[index] : absl::StrCat("code ", index);
  }
};

// What every client needs to know of the server: its address and valid names.
struct Target {
  std::string address;
  int port = 0;
  std::vector<std::string> part_layouts;
  std::vector<std::string> clips;
  int action_size = 0;
  // How large a session may get: envs drawn from [1, max_envs], steps from [1, max_steps].
  int max_envs = 4;
  int max_steps = 150;
};

// One client, seeded with `seed`, running random actions against `target` until `stop`.
void RunSoakClient(const Target& target, uint64_t seed, Tally* tally, const std::atomic<bool>& stop);

}  // namespace modskill

#endif  // MODSKILL_BENCH_SOAK_CLIENT_H_
