#include "client/cpp/simulate_command.h"
#include "common/wire/tensor_codec.h"

#include <chrono>
#include <cstdio>
#include <random>

#include "absl/status/status.h"
#include "client/cpp/cli_output.h"

namespace modskill::cli {

int Simulate(SimulationClient& client, const SimulateOptions& options) {
  const int num_envs = options.num_envs;
  const int steps = options.steps;
  const bool random = options.random_actions;
  v1::SessionConfig config;
  config.set_num_envs(num_envs);
  config.set_seed(options.seed);
  config.set_part_layout(options.part_layout);
  for (const std::string& clip : options.clips) config.add_motions(clip);

  auto session = client.OpenSession(config);
  if (!session.ok()) return Fail(session.status());
  SimulationStream& stream = **session;
  const int action_size = stream.spec().action_size();
  std::printf("session %s at %s: %d envs, %d clips, layout %s, obs %d, action %d\n",
              stream.opened().session_id().c_str(), client.server().c_str(), num_envs,
              stream.opened().clip_names_size(), stream.spec().part_layout().c_str(), stream.spec().obs_size(),
              action_size);
  std::fflush(stdout);

  std::vector<float> actions(static_cast<size_t>(num_envs) * action_size, 0.0f);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::vector<float> reward;
  double reward_sum = 0;
  int64_t reward_count = 0, episodes = 0, truncated = 0;
  double stepping_seconds = 0;
  for (int step = 0; step < steps; ++step) {
    if (random) {
      for (float& a : actions) a = uniform(rng);
    }
    const auto start = std::chrono::steady_clock::now();
    if (absl::Status status = stream.Step(actions.data()); !status.ok()) return Fail(status);
    stepping_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const v1::StepResult& result = stream.result();
    if (absl::Status status = ReadFloatTensor(result.reward(), "StepResult.reward", &reward); !status.ok()) {
      return Fail(status);
    }
    for (float r : reward) reward_sum += r;
    reward_count += static_cast<int64_t>(reward.size());
    if (result.done().dtype() != v1::UINT8 || result.truncated().dtype() != v1::UINT8) {
      return Fail("StepResult.done/truncated: not UINT8");
    }
    for (char d : result.done().data()) episodes += d != 0;
    for (char t : result.truncated().data()) truncated += t != 0;
  }
  const size_t request_bytes = stream.last_request_bytes();
  const size_t response_bytes = stream.last_response_bytes();
  if (absl::Status status = stream.Close(); !status.ok()) return Fail(status);

  const int64_t env_steps = int64_t{num_envs} * steps;
  std::printf("%d steps x %d envs (%s actions) in %.2f s: %.1f env steps/s, %.1f steps/s\n", steps, num_envs,
              random ? "random" : "zero", stepping_seconds,
              stepping_seconds > 0 ? env_steps / stepping_seconds : 0.0,
              stepping_seconds > 0 ? steps / stepping_seconds : 0.0);
  std::printf("mean reward %.4f, episodes ended %lld (%lld truncated)\n",
              reward_count > 0 ? reward_sum / reward_count : 0.0, static_cast<long long>(episodes),
              static_cast<long long>(truncated));
  std::printf("message sizes per step: request %s, response %s\n", FormatBytes(request_bytes).c_str(),
              FormatBytes(response_bytes).c_str());
  return 0;
}

}  // namespace modskill::cli
