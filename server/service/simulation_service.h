// The gRPC face of the simulation core: validates every request at the edge, translates it to
// core calls and core results back to messages. No physics or sampling logic lives here.
#ifndef MODSKILL_SERVER_SERVICE_SIMULATION_SERVICE_H_
#define MODSKILL_SERVER_SERVICE_SIMULATION_SERVICE_H_

#include <memory>
#include <string>

#include "common/policy/policy_checkpoint.h"
#include "modskill/v1/modskill.grpc.pb.h"
#include "server/core/curriculum/adaptive_sampler.h"
#include "server/core/curriculum/plausibility_filter.h"
#include "server/core/curriculum/session_motion_set.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/rollout.h"
#include "server/service/generation_worker.h"
#include "server/service/motion_store.h"
#include "server/service/session_registry.h"

namespace modskill {

// The most reference AMP samples one SampleReferenceAmp may ask for (also bounded by the message
// limit, see the proto).
inline constexpr int kMaxReferenceAmpSamples = 65536;

struct ServiceOptions {
  int threads_per_session = 1;
  int max_sessions = 8;
  int max_envs_per_session = 4096;
  int64_t max_upload_bytes = int64_t{64} << 20;
  int64_t max_response_bytes = int64_t{512} << 20;  // the server's message limit (--max_message_mb)
  // Directories a Rollout's checkpoint_path may name files in (--checkpoint_dir). None: the
  // server reads no checkpoint file a client names; clients send checkpoint_bytes.
  std::vector<std::string> checkpoint_dirs;
  std::string auth_token;  // empty: no authentication
  PhysicsOptions physics;
  // Active skill learning: how each session's clip sampler follows ReportFailures (kUniform: the
  // no-adaptive ablation), and the probability floor: every clip keeps >= sampling_floor / N.
  SamplingScheme sampling = SamplingScheme::kFailureCount;
  double sampling_floor = kDefaultSamplingFloor;  // in [0, 1]
  // Generative resampling: variants of failed clips join each session's motion set
  // (generation.enabled = false: the --no_generative ablation).
  GenerationOptions generation;
  PlausibilityOptions plausibility;
  std::string generator_address;  // external MotionGenerator host:port; empty: built-in only
  absl::Duration generator_timeout = absl::Seconds(10);
  std::string generated_clip_dir;  // also write every generated clip that joins a session here
  int64_t max_saved_generated_clips = 10000;  // files written there over the server's life
  // Clips the library may hold, shipped and uploaded (AddMotions beyond it: RESOURCE_EXHAUSTED).
  // A session holds at most its library clips plus --max_generated_clips variants.
  int max_library_clips = 10000;
};

class SimulationService final : public v1::Simulation::Service {
 public:
  // Fails when the skeleton, layouts or humanoid cannot be built.
  static absl::StatusOr<std::unique_ptr<SimulationService>> Create(const ServiceOptions& options,
                                                                   std::shared_ptr<const MotionLibrary> motions);

  grpc::Status Describe(grpc::ServerContext* context, const v1::DescribeRequest* request,
                        v1::EnvSpec* response) override;
  grpc::Status Simulate(grpc::ServerContext* context,
                        grpc::ServerReaderWriter<v1::SimulateResponse, v1::SimulateRequest>* stream) override;
  grpc::Status ReportFailures(grpc::ServerContext* context, const v1::ReportFailuresRequest* request,
                              v1::SamplerState* response) override;
  grpc::Status SampleReferenceAmp(grpc::ServerContext* context, const v1::SampleReferenceAmpRequest* request,
                                  v1::SampleReferenceAmpResponse* response) override;
  grpc::Status Rollout(grpc::ServerContext* context, const v1::RolloutRequest* request,
                       grpc::ServerWriter<v1::RolloutResponse>* writer) override;
  grpc::Status QueryFamily(grpc::ServerContext* context, const v1::QueryFamilyRequest* request,
                           v1::QueryFamilyResponse* response) override;
  grpc::Status ListMotions(grpc::ServerContext* context, const v1::ListMotionsRequest* request,
                           v1::ListMotionsResponse* response) override;
  grpc::Status AddMotions(grpc::ServerContext* context, const v1::AddMotionsRequest* request,
                          v1::AddMotionsResponse* response) override;
  grpc::Status GetStats(grpc::ServerContext* context, const v1::GetStatsRequest* request,
                        v1::ServerStats* response) override;

  SessionRegistry& registry() { return registry_; }
  GenerationWorker& generation_worker() { return *generation_worker_; }

 private:
  SimulationService(const ServiceOptions& options, std::shared_ptr<const MotionLibrary> motions)
      : options_(options), motions_(std::move(motions)), registry_(options.max_sessions) {}

  grpc::Status CheckAuth(const grpc::ServerContext* context) const;
  absl::StatusOr<PartLayout> Layout(const std::string& name) const;

  // Simulate's phases (simulate_rpc.cc): open the session the config asks for (registered, its
  // envs reset), describe it, then apply one actions message and fill the step's result.
  struct StepScratch;
  absl::StatusOr<std::shared_ptr<SimulationSession>> OpenSession(const grpc::ServerContext& context,
                                                                 const v1::SessionConfig& config, int* amp_frames);
  void DescribeOpenedSession(const SimulationSession& session, int amp_frames, v1::SessionOpened* opened) const;
  absl::Status StepSession(SimulationSession& session, const v1::SimulateRequest& request, int amp_frames,
                           StepScratch& scratch, v1::StepResult* out);

  // Rollout's phases (rollout_rpc.cc): the policy from a path in --checkpoint_dir or bytes, the
  // clips and options the request asks for.
  absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> LoadRolloutPolicy(const v1::RolloutRequest& request) const;
  // The checkpoint_path / checkpoint_bytes oneof of Rollout and QueryFamily (null: unset).
  absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> LoadPolicy(const std::string* path, const std::string* bytes) const;
  absl::StatusOr<RolloutOptions> RolloutOptionsFor(const v1::RolloutRequest& request,
                                                   const ActionMapping& trained) const;

  const ServiceOptions options_;
  MotionStore motions_;
  SessionRegistry registry_;
  std::unique_ptr<HumanoidSpec> skeleton_;
  std::shared_ptr<const HumanoidModel> humanoid_;
  std::unique_ptr<PartLayoutCatalog> layouts_;
  // Last, so that it stops before the skeleton it reads goes away.
  std::unique_ptr<GenerationWorker> generation_worker_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_SIMULATION_SERVICE_H_
