// Generative resampling off the RPC threads: a background thread that turns each planned round
// (a failed clip, a part, a seed) into new clips, with the external generator when one is set
// (--generator) and the built-in displacement-mapping generator otherwise or when the external
// one fails, filters them for plausibility and commits the survivors to the session. A slow or
// dead generator therefore never stalls ReportFailures or a Simulate stream.
#ifndef MODSKILL_SERVER_SERVICE_GENERATION_WORKER_H_
#define MODSKILL_SERVER_SERVICE_GENERATION_WORKER_H_

#include <deque>
#include <memory>
#include <thread>

#include "absl/synchronization/mutex.h"
#include "server/core/curriculum/plausibility_filter.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/service/external_motion_generator.h"
#include "server/service/simulation_session.h"

namespace modskill {

class GenerationWorker {
 public:
  // `external` may be null (built-in generator only). `max_queued`: rounds waiting at most;
  // more are dropped (counted per session) rather than piling up behind a slow generator.
  // `save_dir`: when set, every clip that joins a session is also written there as
  // <session>/<name>.msclip (for inspection and reuse; `modskill-motion inspect` reads them),
  // up to `max_saved` files over the server's life (then saving stops, logged once), so that the
  // disk cannot fill up however long the server runs.
  GenerationWorker(const HumanoidSpec* spec, std::unique_ptr<ExternalMotionGenerator> external,
                   const PlausibilityOptions& filter, std::string save_dir = "", int64_t max_saved = 10000,
                   int max_queued = 256);
  ~GenerationWorker();  // finishes the round in progress, drops the rest
  GenerationWorker(const GenerationWorker&) = delete;
  GenerationWorker& operator=(const GenerationWorker&) = delete;

  // Queues the rounds; those that do not fit are abandoned on the session.
  void Enqueue(const std::shared_ptr<SimulationSession>& session, std::vector<GenerationRequest> rounds);
  // Blocks until the queue is empty and no round is running (tests, benchmarks).
  void WaitIdle();

 private:
  struct Job {
    std::weak_ptr<SimulationSession> session;
    GenerationRequest request;
  };
  void Run();
  // One round: generate candidates, keep the plausible ones, commit them, save what joined.
  void RunRound(SimulationSession& session, const GenerationRequest& request);
  // The external generator's variants, or the built-in generator's (none if both fail).
  std::vector<MotionVariant> GenerateCandidates(SimulationSession& session, const GenerationRequest& request,
                                                GenerationCounters& counters);
  // The candidates that pass the plausibility filter (and the session's discriminator, if any).
  std::vector<MotionVariant> FilterCandidates(SimulationSession& session, const GenerationRequest& request,
                                              std::vector<MotionVariant> candidates, GenerationCounters& counters);
  // Writes the clips that joined the session under --save_generated, up to max_saved_ in all.
  void SaveGenerated(const SimulationSession& session, const std::vector<std::shared_ptr<const MotionClip>>& added);

  const HumanoidSpec* spec_;
  const std::unique_ptr<ExternalMotionGenerator> external_;
  const PlausibilityOptions filter_;
  const std::string save_dir_;
  const int64_t max_saved_;
  int64_t saved_ = 0;  // only the worker's thread touches it
  const int max_queued_;
  absl::Mutex mutex_;
  std::deque<Job> queue_ ABSL_GUARDED_BY(mutex_);
  bool busy_ ABSL_GUARDED_BY(mutex_) = false;
  bool stopping_ ABSL_GUARDED_BY(mutex_) = false;
  std::thread thread_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_GENERATION_WORKER_H_
