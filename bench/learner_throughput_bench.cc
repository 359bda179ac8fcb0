// Learner throughput (issue: "samples/s of inference and of the PPO update for small and paper
// presets", and "end-to-end steps/s of server + learner versus the server alone").
//
// 1. Networks alone, on random observations of the real env spec: inference (normalize,
//    policy means, critic values; no gradients) and the PPO update (forward, losses, backward,
//    Adam step) in samples per second, for the small and paper presets.
// 2. End to end: an in-process server (2 threads) and the trainer (small preset, 256 envs in
//    two sessions), against the same server driven by a learner-like loop with zero actions.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_cat.h"
#include "bench/median.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/policy_enums.h"
#include "learner/critic.h"
#include "learner/modskill_policy.h"
#include "learner/ppo_loss.h"
#include "learner/running_mean_std.h"
#include "learner/trainer.h"
#include "server/core/util/data_paths.h"
#include "server/service/proto_conversions.h"
#include "server/service/server_runner.h"

ABSL_FLAG(int, repeats, 5, "timed repetitions per measurement (median reported)");
ABSL_FLAG(int, iterations, 4, "trainer iterations for the end-to-end measurement");
ABSL_FLAG(bool, paper, true, "also measure the paper preset");
ABSL_FLAG(int, epochs, 0, "PPO epochs for the end-to-end measurement (0: the small preset's)");
ABSL_FLAG(int, discriminator_epochs, 0, "discriminator epochs for the end-to-end measurement (0: the preset's)");
ABSL_FLAG(int, minibatch_size, 0, "PPO minibatch for the end-to-end measurement (0: the small preset's)");
ABSL_FLAG(int, update_threads, -1, "torch threads for the updates (-1: the small preset's)");
ABSL_FLAG(double, amp_reward_weight, -1, "AMP reward weight (-1: the small preset's)");
ABSL_FLAG(int, amp_frames, -1, "AMP frames the discriminator reads (0: all the server sends; -1: the small preset's)");
ABSL_FLAG(bool, networks, true, "measure the networks alone");
ABSL_FLAG(std::vector<std::string>, modes, std::vector<std::string>({"sequential", "during_update"}),
          "end-to-end collection modes to measure side by side: sequential, during_update");

namespace modskill::learner {
namespace {

using Clock = std::chrono::steady_clock;

template <typename F>
double SamplesPerSecond(int samples, int repeats, F&& work) {
  work();  // warm up
  std::vector<double> rates;
  for (int r = 0; r < repeats; ++r) {
    const auto start = Clock::now();
    work();
    rates.push_back(samples / std::chrono::duration<double>(Clock::now() - start).count());
  }
  return Median(rates);
}

void NetworkThroughput(const std::string& preset, const NetworkLayout& layout) {
  ModelConfig config = *ModelConfig::Preset(preset);
  ModSkillPolicy policy(layout, config);
  Critic critic(layout.obs_size, config.critic_hidden);
  RunningMeanStd norm(layout.obs_size);
  std::vector<torch::Tensor> parameters = policy->parameters();
  for (const auto& p : critic->parameters()) parameters.push_back(p);
  torch::optim::Adam adam(parameters, torch::optim::AdamOptions(1e-4));
  const int repeats = absl::GetFlag(FLAGS_repeats);
  for (int batch : {256, 2048, 4096}) {
    const torch::Tensor obs = torch::randn({batch, layout.obs_size});
    const double inference = SamplesPerSecond(batch, repeats, [&] {
      torch::NoGradGuard no_grad;
      const torch::Tensor normalized = norm->Normalize(obs);
      policy->forward(normalized).sum().item<float>();
      critic->forward(normalized).sum().item<float>();
    });
    const torch::Tensor actions = torch::randn({batch, layout.action_size});
    const torch::Tensor old_log_prob = torch::randn({batch}), advantages = torch::randn({batch});
    const torch::Tensor old_values = torch::randn({batch}), returns = torch::randn({batch});
    const double update = SamplesPerSecond(batch, repeats, [&] {
      const torch::Tensor normalized = norm->Normalize(obs);
      const torch::Tensor mean = policy->forward(normalized);
      PpoLossTerms loss = ComputePpoLoss(ModSkillPolicyImpl::LogProb(mean, policy->log_std(), actions), old_log_prob,
                                         advantages, critic->forward(normalized), old_values, returns, 0.2, 0.2, 2.0);
      adam.zero_grad();
      loss.total.backward();
      adam.step();
    });
    std::printf("%-6s batch %5d: inference %9.0f samples/s   PPO update %9.0f samples/s\n", preset.c_str(), batch,
                inference, update);
    std::fflush(stdout);
  }
}

// The networks alone, with one and two torch threads.
void NetworksAlone(const NetworkLayout& layout) {
  for (int threads : {1, 2}) {
    if (!absl::GetFlag(FLAGS_networks)) break;
    SetTorchThreads(threads);
    std::printf("networks alone (%d torch thread(s), OpenBLAS when installed), medians of %d:\n", threads,
                absl::GetFlag(FLAGS_repeats));
    NetworkThroughput("small", layout);
    if (absl::GetFlag(FLAGS_paper)) NetworkThroughput("paper", layout);
  }
}

// The server alone: two sessions of 128 envs stepped back to back with zero actions for 10 s;
// env steps per second.
double ServerAlone(const std::string& address) {
  ClientOptions client_options;
  client_options.server = address;
  auto client = SimulationClient::Connect(client_options);
  // The same action mode as the trainer's, so that both see the same episodes: zero residual
  // actions track the reference open loop.
  v1::SessionConfig session;
  session.set_num_envs(128);
  session.set_action_mode(ToWire(ActionModeOf(*TrainerConfig::ForPreset("small"))));
  auto first = (*client)->OpenSession(session);
  auto second = (*client)->OpenSession(session);
  std::vector<float> zeros(128 * 69, 0.f);
  const auto alone_start = Clock::now();
  int64_t alone_steps = 0;
  while (std::chrono::duration<double>(Clock::now() - alone_start).count() < 10) {
    (void)(*first)->SendActions(zeros.data());
    (void)(*second)->SendActions(zeros.data());
    (void)(*first)->ReceiveResult();
    (void)(*second)->ReceiveResult();
    alone_steps += 256;
  }
  const double alone = alone_steps / std::chrono::duration<double>(Clock::now() - alone_start).count();
  (void)(*first)->Close();
  (void)(*second)->Close();
  return alone;
}

// The small preset on 256 envs of the server at `address`, with the flags' overrides.
TrainerConfig EndToEndConfig(const std::string& address) {
  TrainerConfig config = *TrainerConfig::ForPreset("small");
  config.servers = {address};
  config.envs_per_server = 256;
  config.sessions_per_server = 2;
  config.iterations = absl::GetFlag(FLAGS_iterations);
  config.run_dir = "/tmp/modskill-learner-bench";
  config.checkpoint_every = 1000;
  if (absl::GetFlag(FLAGS_epochs) > 0) config.epochs = absl::GetFlag(FLAGS_epochs);
  if (absl::GetFlag(FLAGS_discriminator_epochs) > 0) config.discriminator_epochs = absl::GetFlag(FLAGS_discriminator_epochs);
  if (absl::GetFlag(FLAGS_minibatch_size) > 0) config.minibatch_size = absl::GetFlag(FLAGS_minibatch_size);
  if (absl::GetFlag(FLAGS_update_threads) >= 0) config.update_threads = absl::GetFlag(FLAGS_update_threads);
  if (absl::GetFlag(FLAGS_amp_frames) >= 0) config.model.amp_frames = absl::GetFlag(FLAGS_amp_frames);
  if (absl::GetFlag(FLAGS_amp_reward_weight) >= 0) {
    config.amp_reward_weight = absl::GetFlag(FLAGS_amp_reward_weight);
    config.task_reward_weight = 1 - config.amp_reward_weight;
  }
  return config;
}

// The modes one after the other on the same server; the first iteration of each (networks
// warming up, no collection yet running during an update) is not counted. Returns the exit code.
int MeasureModes(TrainerConfig config, double alone) {
  for (const std::string& mode : absl::GetFlag(FLAGS_modes)) {
    if (mode != "sequential" && mode != "during_update") {
      return std::fprintf(stderr, "error: --modes: unknown mode '%s'\n", mode.c_str()), 2;
    }
    config.collect_during_update = mode == "during_update";
    auto trainer = Trainer::Create(config);
    if (!trainer.ok()) return std::fprintf(stderr, "error: %s\n", std::string(trainer.status().message()).c_str()), 1;
    std::vector<double> rates, collect, update;
    (void)(*trainer)->Run([&](const IterationStats& s) {
      if (s.iteration == 1) return;
      rates.push_back(s.env_steps_per_second);
      collect.push_back(s.collect_seconds);
      update.push_back(s.update_seconds);
    });
    std::printf("  server + learner, collection %-14s %7.0f env steps/s  (%.2f x server alone); per iteration: "
                "waiting for collection %.2f s, update %.2f s (medians)\n",
                mode == "sequential" ? "then update:" : "during update:", Median(rates), Median(rates) / alone,
                Median(collect), Median(update));
  }
  return 0;
}

int Run() {
  SetTorchThreads(1);
  auto spec = HumanoidSpec::LoadDefault();
  auto humanoid = HumanoidModel::Create(*spec, PhysicsOptions());
  auto catalog = PartLayoutCatalog::LoadDefault(*spec);
  v1::EnvSpec wire_spec;
  ToProto(MakeEnvSpec(**humanoid, *catalog->Get("5part")), **humanoid, &wire_spec);
  NetworksAlone(LayoutFromWireSpec(wire_spec));
  SetTorchThreads(1);

  auto library = MotionLibrary::LoadDefault(*spec);
  ServerOptions options;
  options.port = 0;
  options.service.threads_per_session = 1;  // two sessions of 128: one thread each, two cores
  auto server = StartServer(options, std::make_shared<const MotionLibrary>(*std::move(library)));
  if (!server.ok()) return std::fprintf(stderr, "error: %s\n", std::string(server.status().message()).c_str()), 1;
  const std::string address = absl::StrCat("127.0.0.1:", (*server)->port());
  const double alone = ServerAlone(address);
  const TrainerConfig config = EndToEndConfig(address);
  std::printf("\nend to end, 256 envs (2 sessions of 128, 1 server thread each), small preset, %d iterations of %d steps, "
              "%d PPO + %d discriminator epochs, AMP frames read: %s:\n",
              config.iterations, 256 * config.horizon, config.epochs, config.discriminator_epochs,
              config.model.amp_frames == 0 ? "all" : std::to_string(config.model.amp_frames).c_str());
  std::printf("  server alone (zero actions over gRPC):  %7.0f env steps/s\n", alone);
  if (int code = MeasureModes(config, alone); code != 0) return code;
  (*server)->Shutdown(absl::Seconds(1));
  return 0;
}

}  // namespace
}  // namespace modskill::learner

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return modskill::learner::Run();
}
