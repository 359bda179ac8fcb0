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
#include "server/core/adaptive_sampler.h"
#include "server/core/env_batch.h"
#include "server/core/failure_ledger.h"

namespace modskill {

struct SimulationSession {
  SimulationSession(std::string session_id, std::string client, std::unique_ptr<EnvBatch> envs,
                    std::vector<std::string> names, SamplingScheme sampling = SamplingScheme::kFailureCount,
                    double sampling_floor = kDefaultSamplingFloor)
      : id(std::move(session_id)),
        peer(std::move(client)),
        batch(std::move(envs)),
        clip_names(std::move(names)),
        ledger(static_cast<int>(clip_names.size()), batch->spec().layout.num_parts()),
        adaptive_sampler(static_cast<int>(clip_names.size()), sampling, sampling_floor),
        opened(absl::Now()) {}

  // Hands the stream thread the weights ReportFailures computed (any RPC thread).
  void SetPendingWeights(std::vector<double> weights) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex) {
    pending_weights = std::move(weights);
    weights_pending.store(true, std::memory_order_release);
  }
  // The stream thread, between steps: moves the pending weights (if any) into *weights and
  // returns true. Lock-free when nothing is pending, so the step loop takes no lock.
  bool TakePendingWeights(std::vector<double>* weights) ABSL_LOCKS_EXCLUDED(mutex) {
    if (!weights_pending.load(std::memory_order_acquire)) return false;
    absl::MutexLock lock(&mutex);
    weights->swap(pending_weights);
    weights_pending.store(false, std::memory_order_relaxed);
    return true;
  }

  const std::string id;
  const std::string peer;
  const std::unique_ptr<EnvBatch> batch;  // stepped only by the session's stream
  const std::vector<std::string> clip_names;
  absl::Mutex mutex;
  FailureLedger ledger ABSL_GUARDED_BY(mutex);
  // Fed by ReportFailures. Its weights reach the batch's ClipSampler only through the stream
  // thread (TakePendingWeights before its next Step), never while the batch is stepping.
  AdaptiveSampler adaptive_sampler ABSL_GUARDED_BY(mutex);
  std::vector<double> pending_weights ABSL_GUARDED_BY(mutex);
  std::atomic<bool> weights_pending{false};
  const absl::Time opened;
  std::atomic<int64_t> steps{0};
  std::atomic<int64_t> episodes{0};
  std::atomic<int64_t> physics_resets{0};
  std::atomic<int64_t> failure_reports{0};
};

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
