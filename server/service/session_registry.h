// Live simulation sessions and the server's running totals. A session belongs to one
// Simulate stream; other RPCs (ReportFailures, GetStats) reach it through here.
#ifndef MODSKILL_SERVER_SERVICE_SESSION_REGISTRY_H_
#define MODSKILL_SERVER_SERVICE_SESSION_REGISTRY_H_

#include <atomic>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/service/simulation_session.h"

namespace modskill {

struct ServerTotals {
  int active_sessions = 0;
  int64_t sessions_opened = 0;
  int64_t env_steps = 0;
  double env_steps_per_second = 0;
  int64_t episodes = 0;
  int64_t physics_resets = 0;
  int64_t failure_reports = 0;
  double uptime_seconds = 0;
  std::vector<std::shared_ptr<SimulationSession>> sessions;
};

class SessionRegistry {
 public:
  explicit SessionRegistry(int max_sessions) : max_sessions_(max_sessions), started_(absl::Now()) {}

  // RESOURCE_EXHAUSTED when max_sessions are open. Returns the new session id.
  absl::StatusOr<std::string> Reserve();
  void Release();  // a reservation that did not become a session
  void Register(std::shared_ptr<SimulationSession> session);
  // Folds the session's figures into the totals and forgets it.
  void Close(const std::string& id);
  std::shared_ptr<SimulationSession> Find(const std::string& id) const;

  void AddSteps(int64_t env_steps, int64_t episodes, int64_t physics_resets);
  void AddFailureReports(int64_t reports) { failure_reports_ += reports; }
  ServerTotals Totals();

 private:
  const int max_sessions_;
  const absl::Time started_;
  mutable absl::Mutex mutex_;
  int reserved_ ABSL_GUARDED_BY(mutex_) = 0;
  int64_t next_id_ ABSL_GUARDED_BY(mutex_) = 1;
  int64_t sessions_opened_ ABSL_GUARDED_BY(mutex_) = 0;
  std::map<std::string, std::shared_ptr<SimulationSession>> sessions_ ABSL_GUARDED_BY(mutex_);
  std::deque<std::pair<absl::Time, int64_t>> step_samples_ ABSL_GUARDED_BY(mutex_);
  std::atomic<int64_t> env_steps_{0};
  std::atomic<int64_t> episodes_{0};
  std::atomic<int64_t> physics_resets_{0};
  std::atomic<int64_t> failure_reports_{0};
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SESSION_REGISTRY_H_
