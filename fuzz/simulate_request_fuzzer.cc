// libFuzzer target: the bytes of one Simulate stream message, parsed as v1::SimulateRequest and
// checked as the service checks it (server/service/session_config_validation.cc,
// tensor_codec.cc): a session config through ParseSessionConfig against the shipped layouts with
// the server's default --max_envs_per_session; an action message through ReadFloatTensor against
// the shape of a session of kEnvs envs on the default layout, then its termination distance.
//
// What passes must be what the session is built from: envs within the limit, a known layout,
// a valid termination distance and action mapping, and exactly kEnvs x action_size actions.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/wire/tensor_codec.h"
#include "fuzz/fuzz_service.h"
#include "google/protobuf/stubs/logging.h"
#include "modskill/v1/modskill.pb.h"
#include "server/core/env/env_batch.h"
#include "server/service/session_config_validation.h"

namespace modskill::fuzz {
namespace {

constexpr int kMaxEnvsPerSession = 4096;  // ServiceOptions' default
constexpr int kMaxLibraryClips = 10000;   // ServiceOptions' default
constexpr int64_t kEnvs = 2;              // the session an action message is read for

void FuzzSessionConfig(const v1::SessionConfig& config) {
  const ServiceFixture& fixture = Fixture();
  auto settings = ParseSessionConfig(config, kMaxEnvsPerSession, kMaxLibraryClips, fixture.layouts);
  if (!settings.ok()) {
    const absl::StatusCode code = settings.status().code();
    Check(code == absl::StatusCode::kInvalidArgument || code == absl::StatusCode::kNotFound ||
              code == absl::StatusCode::kResourceExhausted,
          "a bad config is INVALID_ARGUMENT, NOT_FOUND or RESOURCE_EXHAUSTED");
    return;
  }
  Check(settings->num_envs >= 1 && settings->num_envs <= kMaxEnvsPerSession, "num_envs within the limit");
  Check(fixture.env_specs.count(settings->layout.name) == 1, "a shipped layout");
  Check(ValidateTerminationDistance(settings->env.termination_distance).ok(), "a valid termination distance");
  Check(settings->env.action.Validate().ok(), "a valid action mapping");
  Check(settings->env.max_episode_steps >= 0, "max_episode_steps >= 0");
  Check(settings->amp_frames == 0 || settings->amp_frames == 1 || settings->amp_frames == kAmpHistory,
        "amp_frames 0, 1 or the history");
}

void FuzzActions(const v1::SimulateRequest& request) {
  const ServiceFixture& fixture = Fixture();
  const int64_t action_size = fixture.env_specs.at(fixture.layouts.default_name()).action_size;
  std::vector<float> actions;
  if (ReadFloatTensor(request.actions(), "actions", {kEnvs, action_size}, &actions).ok()) {
    Check(actions.size() == static_cast<size_t>(kEnvs * action_size), "kEnvs x action_size actions");
  }
  // A new distance for a curriculum: EnvBatch::SetTerminationDistance's check.
  if (request.termination_distance() != 0) (void)ValidateTerminationDistance(request.termination_distance());
}

void FuzzSimulateRequest(const uint8_t* data, size_t size) {
  v1::SimulateRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return;  // gRPC answers INTERNAL
  if (request.has_config()) FuzzSessionConfig(request.config());
  if (request.has_actions()) FuzzActions(request);
}

}  // namespace
}  // namespace modskill::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Protobuf logs every string field that is not UTF-8; the parse failing is what counts.
  google::protobuf::SetLogHandler(nullptr);
  modskill::fuzz::Fixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  modskill::fuzz::FuzzSimulateRequest(data, size);
  return 0;
}
