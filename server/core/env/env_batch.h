// N tracking envs stepped together by a pool of worker threads, each env writing its row of
// the preallocated batch buffers. Deterministic for a given seed (independently of threads:
// every env has its own random stream).
#ifndef MODSKILL_SERVER_CORE_ENV_ENV_BATCH_H_
#define MODSKILL_SERVER_CORE_ENV_ENV_BATCH_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "server/core/env/batch_buffers.h"
#include "server/core/env/tracking_env.h"
#include "server/core/util/worker_pool.h"

namespace modskill {

struct EnvBatchConfig {
  int num_envs = 64;
  int num_threads = 1;
  uint64_t seed = 0;
  std::string part_layout;  // empty: the catalog's default (5 parts)
  TrackingEnvConfig env;
  PhysicsOptions physics;
};

// The env's reference_frames: in [1, kMaxReferenceFrames], and above 1 in plain tracking only (no
// task, loop_clips, anchor_reference or family); INVALID_ARGUMENT naming reference_frames and
// what it meets otherwise. EnvBatch::Create checks it; session validation calls it for the
// session's env.
absl::Status CheckReferenceFrames(const TrackingEnvConfig& env);

class EnvBatch {
 public:
  // Builds the humanoid from the default skeleton and `config.physics`, and the layout from
  // the shipped catalog.
  static absl::StatusOr<std::unique_ptr<EnvBatch>> Create(const EnvBatchConfig& config,
                                                          std::shared_ptr<const MotionLibrary> motions);
  // With a humanoid and layout chosen by the caller (shared between batches).
  static absl::StatusOr<std::unique_ptr<EnvBatch>> Create(const EnvBatchConfig& config,
                                                          std::shared_ptr<const HumanoidModel> humanoid,
                                                          const PartLayout& layout,
                                                          std::shared_ptr<const MotionLibrary> motions);

  // Starts every env on a sampled clip and frame.
  void Reset();
  // One control step of every env. `actions` is [num_envs, action_size] in part order;
  // a wrong size or a NaN/Inf anywhere rejects the whole batch before any env moves.
  absl::Status Step(absl::Span<const float> actions);

  absl::Status SetClipWeights(absl::Span<const double> weights) { return sampler_.SetWeights(weights); }
  // Replaces the clips new episodes draw from (call between steps, never during one): the
  // library, the id each library clip is reported as (see EnvContext::clip_ids), the reference
  // AMP frames computed from that library and one sampling weight per clip. Episodes in progress
  // finish on the clip they started with. Errors leave the batch unchanged.
  absl::Status SetMotions(std::shared_ptr<const MotionLibrary> motions, std::vector<int> clip_ids,
                          std::shared_ptr<const ReferenceAmpFrames> reference_amp, absl::Span<const double> weights);
  const ClipSampler& sampler() const { return sampler_; }
  // Family sessions: each env's parameters for its next episode, [num_envs, len(spec().family)],
  // each inside its range (INVALID_ARGUMENT naming the row and parameter; FAILED_PRECONDITION
  // outside a family session). Call between steps.
  absl::Status SetFamilyParameters(absl::Span<const float> rows);
  // The termination distance from the next step on (a curriculum; call between steps).
  absl::Status SetTerminationDistance(double distance);
  const TrackingEnvConfig& env_config() const { return context_.config; }
  const std::vector<int>& termination_body_ids() const { return context_.termination_body_ids; }

  const BatchBuffers& buffers() const { return buffers_; }
  const EnvSpec& spec() const { return *context_.spec; }
  const HumanoidModel& humanoid() const { return *context_.humanoid; }
  const MotionLibrary& motions() const { return *context_.motions; }
  std::shared_ptr<const MotionLibrary> shared_motions() const { return context_.motions; }
  const ReferenceAmpFrames& reference_amp() const { return *context_.reference_amp; }
  std::shared_ptr<const ReferenceAmpFrames> shared_reference_amp() const { return context_.reference_amp; }
  int num_envs() const { return static_cast<int>(envs_.size()); }
  int num_threads() const { return pool_->num_threads(); }
  TrackingEnv& env(int i) { return *envs_[i]; }
  EnvRow row(int i) { return EnvRow{&buffers_, i}; }
  int64_t steps() const { return steps_; }
  int64_t physics_resets() const;

 private:
  EnvBatch() = default;

  EnvContext context_;
  ClipSampler sampler_{1};
  std::vector<std::unique_ptr<TrackingEnv>> envs_;
  BatchBuffers buffers_;
  std::unique_ptr<WorkerPool> pool_;
  const float* pending_actions_ = nullptr;
  std::function<void(int)> step_work_;
  std::function<void(int)> reset_work_;
  int64_t steps_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_ENV_BATCH_H_
