// One live simulation session: its env batch (stepped only by its Simulate stream), and what
// other RPCs and the generation worker change about it (failure ledger, adaptive sampler,
// generated clips). Changes reach the batch only through the stream thread, between two steps
// (TakePending), so no env ever sees its clips or weights change mid-step.
#ifndef MODSKILL_SERVER_SERVICE_SIMULATION_SESSION_H_
#define MODSKILL_SERVER_SERVICE_SIMULATION_SESSION_H_

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/core/curriculum/adaptive_sampler.h"
#include "server/core/curriculum/failure_ledger.h"
#include "server/core/curriculum/session_motion_set.h"
#include "server/core/env/env_batch.h"

namespace modskill {

class DiscriminatorScorer;

// What the generation worker did for a session (GenerationStats on the wire).
struct GenerationCounters {
  int64_t requests = 0;
  int64_t generated = 0;
  int64_t rejected = 0;
  std::map<std::string, int64_t> rejected_by_check;
  int64_t evicted = 0;
  int64_t generator_errors = 0;
  std::string last_generator_error;
  int64_t builtin_fallbacks = 0;
  int64_t dropped_requests = 0;
  int64_t stale_reports = 0;  // reports naming a generated clip that had already been evicted
};

// A new motion set for the stream thread to install, with what changed since the last one it
// installed (several commits between two steps merge into one).
struct PendingMotionSet {
  std::shared_ptr<const MotionLibrary> library;
  std::vector<int> clip_ids;
  std::shared_ptr<const ReferenceAmpFrames> reference_amp;
  std::vector<SessionClipInfo> added;
  std::vector<int> removed_ids;
};

// One entry of a ReportFailures call, by clip name.
struct NamedClipReport {
  std::string clip;
  int frame = -1;
  std::vector<float> part_errors;
  bool terminated = true;
  int steps = 0;  // control steps the episode ran; 0: unknown
};

class SimulationSession {
 public:
  SimulationSession(std::string session_id, std::string client, std::unique_ptr<EnvBatch> envs,
                    SamplingScheme sampling, double sampling_floor, const GenerationOptions& generation,
                    uint64_t seed);

  // Validates every report (NOT_FOUND / INVALID_ARGUMENT naming failures[i].field) before
  // recording any, updates the sampler, and returns the generation rounds now due. Reports on
  // evicted generated clips are counted as stale and skipped.
  absl::StatusOr<std::vector<GenerationRequest>> RecordReports(const std::vector<NamedClipReport>& reports)
      ABSL_LOCKS_EXCLUDED(mutex);
  // A finished round: `accepted` clips join the motion set (evicting under the cap); the
  // counters are added to the session's. Returns the clips that joined, under their session names.
  std::vector<std::shared_ptr<const MotionClip>> CommitRound(const std::string& parent,
                                                             std::vector<MotionVariant> accepted,
                                                             const GenerationCounters& counters)
      ABSL_LOCKS_EXCLUDED(mutex);
  // A round that could not start (queue full): frees the parent for a later round.
  void AbandonRound(const std::string& parent) ABSL_LOCKS_EXCLUDED(mutex);

  // The stream thread, between steps: moves pending weights into *weights (true if any) and a
  // pending motion set into *motion_set. Lock-free when nothing is pending.
  bool TakePending(std::vector<double>* weights, std::optional<PendingMotionSet>* motion_set)
      ABSL_LOCKS_EXCLUDED(mutex);

  // The learner's latest discriminator (ReportFailuresRequest.discriminator); null until one came.
  void SetDiscriminator(std::shared_ptr<const DiscriminatorScorer> scorer) ABSL_LOCKS_EXCLUDED(mutex);
  std::shared_ptr<const DiscriminatorScorer> discriminator() const ABSL_LOCKS_EXCLUDED(mutex);

  // For reference AMP samples: the frames of the committed motion set (any thread).
  std::shared_ptr<const ReferenceAmpFrames> reference_amp() const ABSL_LOCKS_EXCLUDED(mutex);

  const std::string id;
  const std::string peer;
  const std::unique_ptr<EnvBatch> batch;  // stepped only by the session's stream
  const std::vector<std::string> clip_names;  // the original clips (SessionOpened.clip_names)
  const absl::Time opened;
  std::atomic<int64_t> steps{0};
  std::atomic<int64_t> episodes{0};
  std::atomic<int64_t> physics_resets{0};
  std::atomic<int64_t> failure_reports{0};

  mutable absl::Mutex mutex;
  SessionMotionSet motion_set ABSL_GUARDED_BY(mutex);
  // Indexed by motion-set slot; remapped when clips join or leave.
  FailureLedger ledger ABSL_GUARDED_BY(mutex);
  AdaptiveSampler adaptive_sampler ABSL_GUARDED_BY(mutex);
  GenerationCounters generation ABSL_GUARDED_BY(mutex);

 private:
  void PublishWeights() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex);

  std::shared_ptr<const ReferenceAmpFrames> reference_amp_ ABSL_GUARDED_BY(mutex);
  std::shared_ptr<const DiscriminatorScorer> discriminator_ ABSL_GUARDED_BY(mutex);
  std::vector<double> pending_weights_ ABSL_GUARDED_BY(mutex);
  std::optional<PendingMotionSet> pending_motion_set_ ABSL_GUARDED_BY(mutex);
  std::atomic<bool> pending_{false};
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SIMULATION_SESSION_H_
