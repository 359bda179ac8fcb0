// The learner end to end against in-process servers: training runs, checkpoints round-trip,
// the exported policy runs in the server, a dead server does not stop training, and a run
// with no server fails with a clear message.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/policy_spec_wire.h"
#include "learner/best_policy_keeper.h"
#include "learner/evaluation.h"
#include "learner/server_pool.h"
#include "learner/learning_rate_decay.h"
#include "learner/policy_import.h"
#include "learner/skill_library.h"
#include "learner/task_evaluation.h"
#include "learner/trainer.h"
#include "tests/server_fixture.h"
#include "tests/trainer_test_config.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;

std::string RunDir(const std::string& name) {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/learner/" + name;
  std::filesystem::remove_all(dir);
  return dir;
}

TrainerConfig SmallConfig(const std::vector<int>& ports, const std::string& run_dir) {
  std::vector<std::string> servers;
  for (int port : ports) servers.push_back(absl::StrCat("127.0.0.1:", port));
  return SmallTestTrainerConfig(servers, run_dir);
}

// Twelve short iterations on deepmimic_walk with the paper's mapping, where every env starts out
// falling: the rise of the return is large and quick. (With residual actions episodes start long;
// bench/learning_bench.sh measures that mode.)
TrainerConfig SingleClipConfig(int port, const std::string& run_dir) {
  TrainerConfig config = SmallConfig({port}, run_dir);
  config.motions = {"deepmimic_walk"};
  config.envs_per_server = 64;
  config.horizon = 16;
  config.minibatch_size = 256;
  config.epochs = 3;
  config.iterations = 12;
  config.learning_rate = 1e-4;
  config.checkpoint_every = 100;
  config.action_mode = "absolute";
  config.termination_bodies = "all";
  return config;
}

// The mean episode return over iterations [begin, end).
double MeanReturn(const std::vector<IterationStats>& history, size_t begin, size_t end) {
  double sum = 0;
  for (size_t i = begin; i < end; ++i) sum += history[i].mean_episode_return;
  return sum / static_cast<double>(end - begin);
}

TEST(LearnerTrainingTest, TrainsCheckpointsAndExportsAPolicyTheServerRuns) {
  auto server = StartTestServer();
  const std::string dir = RunDir("basic");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.report_every = 1;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  // The sessions' sampler states, read while they are open (GetStats lists live sessions only).
  auto watcher = ConnectTo(*server);
  int64_t reported_steps = 0, reports_while_open = 0;
  ASSERT_TRUE((*trainer)
                  ->Run([&](const IterationStats&) {
                    auto open = watcher->GetStats();
                    if (!open.ok()) return;
                    reported_steps = reports_while_open = 0;
                    for (const v1::SessionStats& session : open->sessions()) {
                      for (const v1::ClipSamplingState& clip : session.clips()) {
                        reported_steps += clip.reported_steps();
                        reports_while_open += clip.failures() + clip.successes();
                      }
                    }
                  })
                  .ok());
  EXPECT_EQ((*trainer)->iteration(), 2);
  EXPECT_EQ((*trainer)->env_steps(), 2 * 16 * 8);
  const IterationStats& last = (*trainer)->history().back();
  EXPECT_EQ(last.live_sessions, 2);
  EXPECT_GT(last.mean_task_reward, 0.0);
  EXPECT_TRUE(std::isfinite(last.policy_loss));
  EXPECT_GT(last.discriminator_loss, 0.0);
  EXPECT_TRUE(std::filesystem::exists(dir + "/checkpoint.pt"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/policy.pt"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/config.json"));
  // policy.pt records the action mode it was trained in (the small preset's: residual).
  auto exported = PolicyCheckpoint::LoadFile(dir + "/policy.pt");
  ASSERT_TRUE(exported.ok()) << exported.status();
  EXPECT_EQ((*exported)->spec().action.mode, ActionMode::kResidual);
  EXPECT_DOUBLE_EQ((*exported)->spec().action.residual_scale, config.residual_scale);

  // Every episode that ended was reported to the session's sampler, failures and successes.
  auto client = ConnectTo(*server);
  auto stats = client->GetStats();
  ASSERT_TRUE(stats.ok());
  EXPECT_GT(stats->failure_reports(), 0);
  EXPECT_EQ(stats->failure_reports(), stats->episodes());
  // Each report carried its episode's length: at least one step each, no more than were stepped.
  EXPECT_GE(reported_steps, reports_while_open);
  EXPECT_GT(reports_while_open, 0);
  EXPECT_LE(reported_steps, (*trainer)->env_steps());

  // The exported policy runs in the server, and evaluation reports the paper's metrics.
  auto report = Evaluate(*client, dir + "/policy.pt", *ReadFileToString(dir + "/policy.pt", 1 << 30),
                         {"deepmimic_walk", "deepmimic_run"});
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_EQ(report->clips.size(), 2u);
  EXPECT_GT(report->g_mpjpe_mm, 0);
  EXPECT_EQ(report->success_at_distance.size(), 7u);
  EXPECT_EQ(report->part_names.size(), 5u);
  EXPECT_THAT(report->ToMarkdown("test"), HasSubstr("| Method | Succ"));
  for (size_t k = 1; k < report->success_at_distance.size(); ++k) {
    EXPECT_LE(report->success_at_distance[k].second, report->success_at_distance[k - 1].second);
  }
  EXPECT_TRUE(report->tracked_bodies.empty()) << "a tracker watches every body";
  server->Shutdown(absl::Seconds(1));
}

// A VR tracking policy (here the open-loop reference, in the VR task's observation) is evaluated
// on its tracked bodies: their errors beside every body's, and Succ that agrees with the success
// at 0.5 m (both over the head and hands).
TEST(LearnerTrainingTest, EvaluationOfAVrPolicyReportsItsTrackedBodies) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  auto spec = client->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  const v1::TaskInfo& vr = spec->tasks(4);
  ASSERT_EQ(vr.name(), "vr_tracking");
  spec->set_task(vr.name());
  spec->set_obs_size(spec->self_obs_size() + vr.goal_size());
  ActionMapping residual;
  residual.mode = ActionMode::kResidual;
  auto bytes = AffinePolicyBytes(PolicySpecOf(*spec, residual), {}, {});
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  auto report = Evaluate(*client, "vr open loop", *bytes, {"deepmimic_walk", "deepmimic_backflip", "deepmimic_cartwheel"});
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_THAT(report->tracked_bodies, ::testing::ElementsAre("Head", "L_Hand", "R_Hand"));
  ASSERT_EQ(report->tracked_body_error_mm.size(), 3u);
  double mean = 0;
  for (int k = 0; k < 3; ++k) {
    const auto body = std::find(report->body_names.begin(), report->body_names.end(), report->tracked_bodies[k]);
    EXPECT_DOUBLE_EQ(report->tracked_body_error_mm[k], report->body_error_mm[body - report->body_names.begin()]);
    mean += report->tracked_body_error_mm[k] / 3;
  }
  EXPECT_GT(mean, 0);
  EXPECT_DOUBLE_EQ(report->tracked_g_mpjpe_mm, mean);
  EXPECT_DOUBLE_EQ(report->success_at_distance[0].second, report->success_rate);
  const std::string markdown = report->ToMarkdown("vr");
  EXPECT_THAT(markdown, HasSubstr("| Tracked body | E_g-mpjpe (mm) |"));
  EXPECT_THAT(markdown, HasSubstr("over the tracked bodies (Head, L_Hand, R_Hand)"));
  EXPECT_THAT(report->ToJson(), HasSubstr("tracked_g_mpjpe_mm"));
  server->Shutdown(absl::Seconds(1));
}

TEST(LearnerTrainingTest, CheckpointRoundTripAndResume) {
  auto server = StartTestServer();
  const std::string dir = RunDir("resume");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  // A curriculum that starts at 2 m on a 24-frame clip: within 16 steps episodes reach the clip's
  // end without failing, so the distance tightens (with the 20 long clips, whether any episode
  // ended in time depended on the machine's speed).
  config.motions = {"deepmimic_run"};
  config.curriculum_start = 2.0;
  config.curriculum_end = 0.25;
  auto first = Trainer::Create(config);
  ASSERT_TRUE(first.ok());
  ASSERT_TRUE((*first)->Run().ok());
  const torch::Tensor probe = torch::randn({4, 934});
  const torch::Tensor before = (*first)->policy()->forward((*first)->obs_norm()->Normalize(probe)).detach();

  config.resume = true;
  config.iterations = 1;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ((*resumed)->iteration(), 2);
  EXPECT_EQ((*resumed)->env_steps(), (*first)->env_steps());
  // The curriculum continues where it stopped.
  EXPECT_NE((*first)->termination_distance(), 2.0);
  EXPECT_DOUBLE_EQ((*resumed)->termination_distance(), (*first)->termination_distance());
  const torch::Tensor after = (*resumed)->policy()->forward((*resumed)->obs_norm()->Normalize(probe)).detach();
  EXPECT_TRUE(torch::equal(before, after));
  ASSERT_TRUE((*resumed)->Run().ok());
  EXPECT_EQ((*resumed)->iteration(), 3);

  // A run resumes in the action mode it was trained in; another is refused, naming the flag.
  TrainerConfig absolute = config;
  absolute.action_mode = "absolute";
  auto switched = Trainer::Create(absolute);
  ASSERT_FALSE(switched.ok());
  EXPECT_EQ(switched.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(switched.status().message()), HasSubstr("--action_mode residual"));

  // A damaged checkpoint is an error, not a crash; the good one is untouched.
  const std::string damaged = dir + "/damaged.pt";
  std::string bytes = *ReadFileToString(dir + "/checkpoint.pt", 1 << 30);
  ASSERT_TRUE(WriteFileAtomically(damaged, bytes.substr(0, bytes.size() / 2)).ok());
  absl::Status status = (*resumed)->LoadCheckpoint(damaged);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr("damaged.pt"));
  // So is a resume from a run directory whose checkpoint is damaged (read once, before the networks).
  TrainerConfig damaged_run = config;
  damaged_run.run_dir = RunDir("damaged_run");
  std::filesystem::create_directories(damaged_run.run_dir);
  ASSERT_TRUE(WriteFileAtomically(damaged_run.run_dir + "/checkpoint.pt", bytes.substr(0, bytes.size() / 2)).ok());
  auto refused = Trainer::Create(damaged_run);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("damaged_run/checkpoint.pt: not a loadable training"));
  // A checkpoint from another layout does not load into this one.
  TrainerConfig three = SmallConfig({server->port()}, RunDir("three"));
  three.part_layout = "3part";
  three.iterations = 1;
  auto other = Trainer::Create(three);
  ASSERT_TRUE(other.ok());
  ASSERT_TRUE((*other)->Run().ok());
  EXPECT_FALSE((*resumed)->LoadCheckpoint(RunDir("three") + "/checkpoint.pt").ok());
  server->Shutdown(absl::Seconds(1));
}

// --amp_frames: the discriminator reads the newest frames of the server's AMP history, its
// checkpoint records the width, and a resumed run reads as many frames unless told otherwise,
// which is refused naming the flag.
TEST(LearnerTrainingTest, DiscriminatorReadsTheNewestAmpFramesAcrossAResume) {
  auto server = StartTestServer();
  const std::string dir = RunDir("amp_frames");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.iterations = 1;
  config.model.amp_frames = 2;
  auto first = Trainer::Create(config);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE((*first)->Run().ok());
  const auto input_width = [](Trainer& trainer) { return trainer.discriminator()->mlp()->layers().front()->weight.size(1); };
  constexpr int64_t per_frame = 232;  // the 24-body humanoid's AMP features per frame
  EXPECT_EQ(input_width(**first), 2 * per_frame);
  const IterationStats& stats = (*first)->history().back();
  EXPECT_TRUE(std::isfinite(stats.discriminator_loss));
  EXPECT_NE(stats.discriminator_loss, 0) << "the discriminator stepped";
  auto checkpoint = LoadCheckpointArchive(*ReadFileToString(dir + "/checkpoint.pt", kMaxCheckpointBytes), "checkpoint");
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_EQ(*CheckpointAmpObsSize(**checkpoint, "checkpoint"), 2 * per_frame);

  config.resume = true;
  config.model.amp_frames = 0;  // the preset's: a resumed run keeps its checkpoint's frames
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ(input_width(**resumed), 2 * per_frame);
  EXPECT_EQ((*resumed)->config().model.amp_frames, 2);
  ASSERT_TRUE((*resumed)->Run().ok());

  config.model.amp_frames = 3;
  config.amp_frames_given = true;
  auto refused = Trainer::Create(config);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("--amp_frames 3"));

  TrainerConfig too_many = SmallConfig({server->port()}, RunDir("amp_frames_too_many"));
  too_many.model.amp_frames = 11;
  auto beyond = Trainer::Create(too_many);
  ASSERT_FALSE(beyond.ok());
  EXPECT_EQ(beyond.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(beyond.status().message()), HasSubstr("--amp_frames: 11 is not in [0, 10]"));
  server->Shutdown(absl::Seconds(1));
}

// --reference_frames: the sessions observe that many upcoming frames, policy.pt records the count,
// and the server's Rollout runs the policy with as many (a 1-frame env would not fit it); skills
// that observe more than one frame are refused for a task, naming the count.
TEST(LearnerTrainingTest, ReferenceFramesTrainExportAndRollOutWithTheirCount) {
  auto server = StartTestServer();
  const std::string dir = RunDir("reference_frames");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.iterations = 1;
  config.reference_frames = 3;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run().ok());
  EXPECT_EQ((*trainer)->spec().obs_size(), 358 + 3 * 576);
  EXPECT_EQ((*trainer)->spec().reference_frames(), 3);
  auto exported = PolicyCheckpoint::LoadFile(dir + "/policy.pt");
  ASSERT_TRUE(exported.ok()) << exported.status();
  EXPECT_EQ((*exported)->spec().reference_frames, 3);
  EXPECT_EQ((*exported)->spec().obs_size, 358 + 3 * 576);
  auto client = ConnectTo(*server);
  auto report = Evaluate(*client, dir + "/policy.pt", *ReadFileToString(dir + "/policy.pt", 1 << 30),
                         {"deepmimic_walk"});
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_EQ(report->clips.size(), 1u);
  EXPECT_GT(report->clips[0].steps(), 0);

  auto skills = SkillLibrary::Load(dir + "/policy.pt");
  ASSERT_FALSE(skills.ok());
  EXPECT_THAT(std::string(skills.status().message()), HasSubstr("observing 3 reference frames"));

  // A resume without the flag observes as many frames as its checkpoint; with another count it is
  // refused, naming the flag.
  config.resume = true;
  config.reference_frames = 1;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ((*resumed)->config().reference_frames, 3);
  EXPECT_EQ((*resumed)->spec().obs_size(), 358 + 3 * 576);
  resumed->reset();
  config.reference_frames_given = true;
  auto other_count = Trainer::Create(config);
  ASSERT_FALSE(other_count.ok());
  EXPECT_EQ(other_count.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(other_count.status().message()), HasSubstr("resume with --reference_frames 3, not 1"));
  server->Shutdown(absl::Seconds(1));
}

// --controller_hidden / --critic_hidden: the widths build the networks, travel in the
// checkpoint, and a resume with other widths is refused with the flag to repeat.
TEST(LearnerTrainingTest, NetworkWidthsTrainAndResumeOnlyWithTheirOwn) {
  auto server = StartTestServer();
  const std::string dir = RunDir("network_widths");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.iterations = 1;
  config.model.controller_hidden = {48, 24};
  config.model.critic_hidden = {40};
  auto first = Trainer::Create(config);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE((*first)->Run().ok());
  for (const PartController& controller : (*first)->policy()->controllers()) {
    ASSERT_EQ(controller->mlp()->layers().size(), 3u);
    EXPECT_EQ(controller->mlp()->layers()[0]->weight.size(0), 48);
    EXPECT_EQ(controller->mlp()->layers()[1]->weight.size(0), 24);
  }
  EXPECT_EQ((*first)->critic()->parameters().front().size(0), 40) << "the first layer of the critic's MLP";

  config.resume = true;
  auto same = Trainer::Create(config);
  ASSERT_TRUE(same.ok()) << same.status();
  ASSERT_TRUE((*same)->Run().ok());

  TrainerConfig preset_widths = SmallConfig({server->port()}, dir);
  preset_widths.resume = true;
  auto refused = Trainer::Create(preset_widths);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("resume with --controller_hidden 48,24, not 256,128"));
  server->Shutdown(absl::Seconds(1));
}

// --normalize_value: the critic learns returns in units of their running statistics, which the
// update fills; a resumed run keeps the checkpoint's mode whatever the flag says, so its critic's
// outputs keep their meaning.
TEST(LearnerTrainingTest, NormalizedValueTrainsAndResumesInItsMode) {
  auto server = StartTestServer();
  const std::string dir = RunDir("normalize_value");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.normalize_value = true;
  auto first = Trainer::Create(config);
  ASSERT_TRUE(first.ok()) << first.status();
  std::vector<double> value_losses;
  ASSERT_TRUE((*first)->Run([&](const IterationStats& stats) { value_losses.push_back(stats.value_loss); }).ok());
  ASSERT_TRUE((*first)->critic()->normalizes_returns());
  RunningMeanStdImpl& returns = (*first)->critic()->return_statistics();
  EXPECT_GT(returns.count().item<double>(), 0);
  EXPECT_GT(returns.mean().item<double>(), 0) << "imitation rewards are positive";
  for (double loss : value_losses) EXPECT_TRUE(std::isfinite(loss));
  const torch::Tensor probe = (*first)->obs_norm()->Normalize(torch::randn({4, 934}));
  const torch::Tensor before = (*first)->critic()->forward(probe).detach();

  config.resume = true;
  config.normalize_value = false;
  config.iterations = 1;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_TRUE((*resumed)->critic()->normalizes_returns());
  EXPECT_TRUE((*resumed)->config().normalize_value);
  EXPECT_TRUE(torch::equal((*resumed)->critic()->forward(probe).detach(), before));
  server->Shutdown(absl::Seconds(1));
}

// --learning_rate_decay_steps: each update's step size follows the env steps before it, down to
// the floor, and a resumed run continues the decay where its checkpoint's steps left it.
TEST(LearnerTrainingTest, LearningRateDecaysOverEnvStepsAcrossAResume) {
  auto server = StartTestServer();
  TrainerConfig config = SmallConfig({server->port()}, RunDir("learning_rate_decay"));
  config.iterations = 2;
  config.learning_rate = 2e-4;
  config.learning_rate_floor = 0.25;
  const int64_t per_iteration = static_cast<int64_t>(config.envs_per_server) * config.horizon;
  config.learning_rate_decay_steps = 2 * per_iteration;
  const LearningRateDecay decay{2e-4, config.learning_rate_decay_steps, 0.25};
  std::vector<IterationStats> history;
  auto first = Trainer::Create(config);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE((*first)->Run([&](const IterationStats& stats) { history.push_back(stats); }).ok());
  config.resume = true;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_TRUE((*resumed)->Run([&](const IterationStats& stats) { history.push_back(stats); }).ok());
  ASSERT_EQ(history.size(), 4u);
  int64_t steps_before = 0;
  for (const IterationStats& stats : history) {
    EXPECT_NEAR(stats.learning_rate, decay.RateAt(steps_before), 1e-12) << "iteration " << stats.iteration;
    steps_before = stats.env_steps;
  }
  EXPECT_DOUBLE_EQ(history[0].learning_rate, 2e-4);
  EXPECT_LT(history[1].learning_rate, history[0].learning_rate);
  EXPECT_NEAR(history[3].learning_rate, 5e-5, 1e-12) << "past decay_steps the floor holds";
  server->Shutdown(absl::Seconds(1));
}

// --critic_learning_rate: the critic steps at its own rate, the policy at --learning_rate; a
// checkpoint resumes only with the same optimizer groups, and says which flag differs.
TEST(LearnerTrainingTest, CriticLearningRateIsTheCriticsOwnStepSize) {
  auto server = StartTestServer();
  TrainerConfig config = SmallConfig({server->port()}, RunDir("critic_learning_rate"));
  config.iterations = 1;
  config.learning_rate = 1e-9;
  config.critic_learning_rate = 1e-3;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  const auto copy = [](const std::vector<torch::Tensor>& params) {
    std::vector<torch::Tensor> copies;
    for (const torch::Tensor& p : params) copies.push_back(p.detach().clone());
    return copies;
  };
  const auto largest_change = [](const std::vector<torch::Tensor>& before, const std::vector<torch::Tensor>& after) {
    double largest = 0;
    for (size_t i = 0; i < before.size(); ++i) {
      largest = std::max(largest, (after[i] - before[i]).abs().max().item<double>());
    }
    return largest;
  };
  const std::vector<torch::Tensor> policy_before = copy((*trainer)->policy()->parameters());
  const std::vector<torch::Tensor> critic_before = copy((*trainer)->critic()->parameters());
  ASSERT_TRUE((*trainer)->Run([](const IterationStats&) {}).ok());
  EXPECT_DOUBLE_EQ((*trainer)->history().back().critic_learning_rate, 1e-3);
  EXPECT_LT(largest_change(policy_before, (*trainer)->policy()->parameters()), 1e-6);
  EXPECT_GT(largest_change(critic_before, (*trainer)->critic()->parameters()), 1e-5);

  config.resume = true;
  config.critic_learning_rate = 0;
  config.critic_learning_rate_given = true;
  auto without = Trainer::Create(config);
  ASSERT_FALSE(without.ok());
  EXPECT_EQ(without.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(without.status().message(), HasSubstr("--critic_learning_rate"));

  // Not given: the resumed run goes on at its checkpoint's rate.
  config.critic_learning_rate_given = false;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_TRUE((*resumed)->Run([](const IterationStats&) {}).ok());
  EXPECT_DOUBLE_EQ((*resumed)->config().critic_learning_rate, 1e-3);
  EXPECT_DOUBLE_EQ((*resumed)->history().back().critic_learning_rate, 1e-3);
  server->Shutdown(absl::Seconds(1));
}

// --gamma and --lambda stay with a run: a resume without them goes on with the checkpoint's, a
// resume with them takes the flags'.
TEST(LearnerTrainingTest, ReturnSettingsStayWithTheRunAcrossAResume) {
  auto server = StartTestServer();
  TrainerConfig config = SmallConfig({server->port()}, RunDir("return_settings"));
  config.iterations = 1;
  config.gamma = 0.9, config.gamma_given = true;
  config.lambda = 0.8, config.lambda_given = true;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run([](const IterationStats&) {}).ok());

  config.resume = true;
  config.gamma = 0.99, config.gamma_given = false;
  config.lambda = 0.95, config.lambda_given = false;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_TRUE((*resumed)->Run([](const IterationStats&) {}).ok());
  EXPECT_DOUBLE_EQ((*resumed)->config().gamma, 0.9);
  EXPECT_DOUBLE_EQ((*resumed)->config().lambda, 0.8);

  config.gamma = 0.97, config.gamma_given = true;
  auto changed = Trainer::Create(config);
  ASSERT_TRUE(changed.ok()) << changed.status();
  EXPECT_DOUBLE_EQ((*changed)->config().gamma, 0.97);
  EXPECT_DOUBLE_EQ((*changed)->config().lambda, 0.8);
  server->Shutdown(absl::Seconds(1));
}

// A run's physics (the servers' rate and servos) is part of what it learned: policy.pt and
// checkpoint.pt record it, a resume against a server with other servos is refused, and a server
// whose physics differs from the run's other servers' is left out.
TEST(LearnerTrainingTest, ARunKeepsThePhysicsItTrainedUnder) {
  auto server = StartTestServer();
  const std::string dir = RunDir("physics");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.iterations = 1;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run([](const IterationStats&) {}).ok());
  auto exported = PolicyCheckpoint::LoadFile(dir + "/policy.pt");
  ASSERT_TRUE(exported.ok()) << exported.status();
  EXPECT_NEAR((*exported)->spec().physics.physics_dt, 1.0 / 120, 1e-12);
  EXPECT_EQ((*exported)->spec().physics.pd_mode, "position_implicit");
  server->Shutdown(absl::Seconds(1));

  ServerOptions stiff;
  stiff.service.physics.pd_gain_scale = 2;
  auto stiff_server = StartTestServer(stiff);
  config.servers = {absl::StrCat("127.0.0.1:", stiff_server->port())};
  config.resume = true;
  auto resumed = Trainer::Create(config);
  ASSERT_FALSE(resumed.ok());
  EXPECT_EQ(resumed.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(resumed.status().message()),
              HasSubstr("checkpoint.pt: trained with pd_gain_scale 1 against this server's 2"));

  // A server whose physics differs from the others' is refused by name, as one whose sizes
  // differ is: the pool leaves it out (and keeps retrying it) while the run trains on the rest.
  auto plain_server = StartTestServer();
  auto plain_spec = ConnectTo(*plain_server)->Describe();
  auto stiff_spec = ConnectTo(*stiff_server)->Describe();
  ASSERT_TRUE(plain_spec.ok() && stiff_spec.ok());
  EXPECT_DOUBLE_EQ(stiff_spec->physics().pd_gain_scale(), 2);
  EXPECT_TRUE(ServerPool::CheckSameEnv("a", *plain_spec, *plain_spec).ok());
  const absl::Status mixed = ServerPool::CheckSameEnv("127.0.0.1:9", *stiff_spec, *plain_spec);
  EXPECT_EQ(mixed.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(mixed.message(), "127.0.0.1:9: simulates with pd_gain_scale 2 against the other servers' 1; "
                             "the server's --pd_gain_scale sets it");
  TrainerConfig both = SmallConfig({plain_server->port(), stiff_server->port()}, RunDir("mixed_physics"));
  both.iterations = 1;
  auto trainer_of_both = Trainer::Create(both);
  ASSERT_TRUE(trainer_of_both.ok()) << trainer_of_both.status();
  ASSERT_TRUE((*trainer_of_both)->Run([](const IterationStats&) {}).ok());
  EXPECT_EQ(ConnectTo(*stiff_server)->GetStats()->env_steps(), 0);
  EXPECT_GT(ConnectTo(*plain_server)->GetStats()->env_steps(), 0);
  stiff_server->Shutdown(absl::Seconds(1));
  plain_server->Shutdown(absl::Seconds(1));
}

class ServerFailoverTest : public ::testing::TestWithParam<bool> {};

// Both collection modes: sequential, and collecting on its own thread during the update (where a
// server dies while the other thread streams to it).
TEST_P(ServerFailoverTest, KillingOneOfTwoServersDoesNotStopTraining) {
  auto a = StartTestServer();
  ServerOptions options_b;
  auto b = StartTestServer(options_b);
  const int port_b = b->port();
  TrainerConfig config = SmallConfig({a->port(), port_b}, RunDir(GetParam() ? "failover_during" : "failover"));
  config.iterations = 10;
  config.collect_during_update = GetParam();
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  std::vector<int> live;
  std::unique_ptr<RunningServer> restarted;
  absl::Status status = (*trainer)->Run([&](const IterationStats& stats) {
    live.push_back(stats.live_sessions);
    if (stats.iteration == 2) b->Shutdown(absl::ZeroDuration());  // server B dies
    if (stats.iteration == 4) {
      // ...and comes back on the same port.
      ServerOptions again;
      again.port = port_b;
      auto started = StartServer(again, DefaultMotions());
      ASSERT_TRUE(started.ok()) << started.status();
      restarted = *std::move(started);
    }
    // Iterations as long as real ones, so that the retry backoff (1 s, 2 s, ...) comes due.
    if (stats.iteration >= 4) absl::SleepFor(absl::Milliseconds(400));
  });
  ASSERT_TRUE(status.ok()) << status;
  EXPECT_EQ((*trainer)->iteration(), 10);
  ASSERT_EQ(live.size(), 10u);
  EXPECT_EQ(live[0], 4);
  EXPECT_EQ(live[1], 4);
  // Collecting during the update, iteration 3's collection may have finished before B died.
  EXPECT_EQ(live[GetParam() ? 4 : 3], 2) << "after B died only A's sessions take part";
  EXPECT_EQ(live.back(), 4) << "B rejoins after it comes back";
  a->Shutdown(absl::Seconds(1));
  restarted->Shutdown(absl::Seconds(1));
}

INSTANTIATE_TEST_SUITE_P(CollectionModes, ServerFailoverTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "CollectDuringUpdate" : "Sequential";
                         });

TEST(LearnerTrainingTest, NoServerFailsWithAClearMessageAfterTheTimeout) {
  TrainerConfig config = SmallConfig({1}, RunDir("noserver"));  // nothing listens on port 1
  config.server_timeout_s = 1.5;
  const absl::Time start = absl::Now();
  auto trainer = Trainer::Create(config);
  ASSERT_FALSE(trainer.ok());
  EXPECT_EQ(trainer.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr("no simulation server answered"));
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr("127.0.0.1:1"));
  EXPECT_LT(absl::Now() - start, absl::Seconds(15));
}

// A session every server refuses (here an unknown clip) cannot be cured by waiting: the server's
// message comes back at once, not after --server_timeout_s.
TEST(LearnerTrainingTest, ASessionEveryServerRefusesFailsAtOnce) {
  auto server = StartTestServer();
  TrainerConfig config = SmallConfig({server->port()}, RunDir("refused"));
  config.motions = {"deepmimic_walk", "no_such_clip"};
  config.server_timeout_s = 60;
  const absl::Time start = absl::Now();
  auto trainer = Trainer::Create(config);
  ASSERT_FALSE(trainer.ok());
  EXPECT_NE(trainer.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr("every server refused the session"));
  EXPECT_THAT(std::string(trainer.status().message()), HasSubstr("no_such_clip"));
  EXPECT_LT(absl::Now() - start, absl::Seconds(10));
}

TEST(LearnerTrainingTest, BadConfigurationsAreClearErrors) {
  TrainerConfig config = SmallConfig({1}, "");
  auto no_dir = Trainer::Create(config);
  ASSERT_FALSE(no_dir.ok());
  EXPECT_THAT(std::string(no_dir.status().message()), HasSubstr("run_dir"));
  config = SmallConfig({1}, "/proc/modskill-cannot-write-here");
  auto unwritable = Trainer::Create(config);
  ASSERT_FALSE(unwritable.ok());
  EXPECT_THAT(std::string(unwritable.status().message()), HasSubstr("run_dir"));
  config = SmallConfig({}, RunDir("x"));
  EXPECT_THAT(std::string(Trainer::Create(config).status().message()), HasSubstr("servers"));
  EXPECT_FALSE(TrainerConfig::ForPreset("huge").ok());
  // Action modes and termination: each bad value names its flag before any server is contacted.
  struct Bad {
    std::function<void(TrainerConfig*)> mutate;
    std::string flag;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Bad> bad = {
      {[](TrainerConfig* c) { c->action_mode = "sideways"; }, "--action_mode"},
      {[&](TrainerConfig* c) { c->residual_scale = nan; }, "--residual_scale"},
      {[](TrainerConfig* c) { c->residual_scale = 0; }, "--residual_scale"},
      {[](TrainerConfig* c) { c->residual_scale = -1; }, "--residual_scale"},
      {[](TrainerConfig* c) { c->termination_distance = 0; }, "--termination_distance"},
      {[](TrainerConfig* c) { c->termination_distance = 150; }, "--termination_distance"},
      {[](TrainerConfig* c) { c->termination_bodies = "toes"; }, "--termination_bodies"},
      {[](TrainerConfig* c) { c->learning_rate_decay_steps = -1; }, "--learning_rate_decay_steps"},
      {[](TrainerConfig* c) { c->learning_rate_floor = 0; }, "--learning_rate_floor"},
      {[](TrainerConfig* c) { c->learning_rate_floor = 1.5; }, "--learning_rate_floor"},
      {[&](TrainerConfig* c) { c->learning_rate_floor = nan; }, "--learning_rate_floor"},
      {[](TrainerConfig* c) { c->critic_learning_rate = -1e-4; }, "--critic_learning_rate"},
      {[&](TrainerConfig* c) { c->critic_learning_rate = nan; }, "--critic_learning_rate"},
      {[](TrainerConfig* c) { c->gamma = 0; }, "--gamma"},
      {[](TrainerConfig* c) { c->gamma = 1.5; }, "--gamma"},
      {[&](TrainerConfig* c) { c->gamma = nan; }, "--gamma"},
      {[](TrainerConfig* c) { c->lambda = -0.1; }, "--lambda"},
      {[&](TrainerConfig* c) { c->lambda = nan; }, "--lambda"},
      {[](TrainerConfig* c) { c->energy_weight = -1; }, "--energy_weight"},
      {[&](TrainerConfig* c) { c->energy_weight = nan; }, "--energy_weight"},
      {[](TrainerConfig* c) { c->model.amp_frames = -2; }, "--amp_frames"},
      {[](TrainerConfig* c) { c->imitation_kernels.rot = -1; }, "--imitation_kernels"},
      {[](TrainerConfig* c) { c->noise_hold_steps = 0; }, "--noise_hold_steps"},
      {[&](TrainerConfig* c) { c->imitation_kernels.pos = nan; }, "--imitation_kernels"},
      {[](TrainerConfig* c) { c->model.controller_hidden = {256, 0}; }, "--controller_hidden"},
      {[](TrainerConfig* c) { c->model.critic_hidden = {-3}; }, "--critic_hidden"},
      {[](TrainerConfig* c) { c->curriculum_start = 0.25, c->curriculum_end = 1.0; }, "--termination_curriculum"},
      {[&](TrainerConfig* c) { c->curriculum_start = nan, c->curriculum_end = 0.25; }, "--termination_curriculum"},
      {[](TrainerConfig* c) { c->task_reach_box_size = 5; }, "--task_reach_box_size"},
      {[&](TrainerConfig* c) { c->task_reach_box_size = nan; }, "--task_reach_box_size"},
      {[](TrainerConfig* c) { c->task_reach_center = {0.3, 0.1}; }, "--task_reach_center"},
      {[](TrainerConfig* c) { c->task_reach_center = {0, 0, 0.5}; }, "--task_reach_center"},  // 2 m box underground
      {[](TrainerConfig* c) { c->task_reach_box_size = 3, c->task_reach_center = {2, 0, 1.5}; }, "--task_reach_center"},
      {[](TrainerConfig* c) { c->task_parts = {"R_Arm"}; }, "--task_parts"},  // tracking has no task head
      {[](TrainerConfig* c) { c->task_teacher = "teacher.txt"; }, "--task_teacher: reach only"},
      {[](TrainerConfig* c) { c->task_teacher_weight = -1; }, "--task_teacher_weight"},
      {[&](TrainerConfig* c) { c->task_teacher_weight = nan; }, "--task_teacher_weight"},
      {[](TrainerConfig* c) { c->task_teacher_steps = -5; }, "--task_teacher_steps"},
      // The server's bounds on the settings the server would use (its defaults where a flag is 0).
      {[](TrainerConfig* c) { c->task_min_speed = -1; }, "--task_min_speed"},
      {[](TrainerConfig* c) { c->task_min_speed = 4; }, "min_speed = 4"},  // above the server's default 3 m/s
      {[&](TrainerConfig* c) { c->task_max_goal_interval_s = nan; }, "--task_max_goal_interval_s"},
      {[](TrainerConfig* c) { c->task_min_goal_interval_s = 6; }, "--task_max_goal_interval_s"},
      {[](TrainerConfig* c) { c->task_steering_rate = -30; }, "--task_steering_rate"},
      {[](TrainerConfig* c) { c->reference_frames = 0; }, "--reference_frames: 0 is not in [1, 8]"},
      {[](TrainerConfig* c) { c->reference_frames = 9; }, "--reference_frames: 9 is not in [1, 8]"},
      {[](TrainerConfig* c) { c->reference_frames = 2, c->loop_clips = true; }, "--reference_frames: 2 with --loop_clips"},
      {[](TrainerConfig* c) { c->reference_frames = 2, c->task = "steer", c->skills = "skills.pt"; },
       "--reference_frames: tracking only"},
      {[&](TrainerConfig* c) { c->task_steering_rate = nan; }, "--task_steering_rate"},
      {[](TrainerConfig* c) {
         c->task = "reach", c->skills = "skills.pt", c->task_parts = {"R_Arm"}, c->model.task_skill_prior = false;
       },
       "--task_parts"},
      {[](TrainerConfig* c) {
         c->model.whole_body = true;
         c->model.controller_input = ModelConfig::ControllerInput::kProprioception;
       },
       "--controller_input"},
  };
  for (const Bad& b : bad) {
    TrainerConfig broken = SmallConfig({1}, RunDir("bad"));
    b.mutate(&broken);
    const absl::Status status = broken.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << b.flag;
    EXPECT_THAT(std::string(status.message()), HasSubstr(b.flag));
    EXPECT_FALSE(Trainer::Create(broken).ok()) << b.flag;
  }
}

// --imitation_kernels: TERM=K pairs, each term once; the text round-trips.
TEST(LearnerTrainingTest, ParsesImitationKernels) {
  auto kernels = ParseImitationKernels("pos=400,ang_vel=0.5");
  ASSERT_TRUE(kernels.ok()) << kernels.status();
  EXPECT_DOUBLE_EQ(kernels->pos, 400);
  EXPECT_DOUBLE_EQ(kernels->rot, 0);
  EXPECT_DOUBLE_EQ(kernels->ang_vel, 0.5);
  EXPECT_EQ(ImitationKernelsText(*kernels), "pos=400,ang_vel=0.5");
  EXPECT_FALSE(ParseImitationKernels("").value().any());
  for (const char* bad : {"pos", "pos=x", "hand=3", "pos=1,pos=2", "rot=-1", "vel=nan", "pos=20000", "pos=1,"}) {
    auto parsed = ParseImitationKernels(bad);
    ASSERT_FALSE(parsed.ok()) << bad;
    EXPECT_THAT(std::string(parsed.status().message()), HasSubstr("--imitation_kernels")) << bad;
  }
  TrainerConfig task = *TrainerConfig::ForPreset("small");
  task.servers = {"localhost:1"};
  task.run_dir = "/tmp";
  task.task = "reach";
  task.skills = "skills.pt";
  task.imitation_kernels.pos = 400;
  EXPECT_THAT(std::string(task.Validate().message()), HasSubstr("--imitation_kernels: task reach"));
}

// A few iterations on one clip: the mean episode return rises (measured with this seed:
// about 1.20 over the first three iterations, 1.47 over the last three; every env starts out
// falling within a few steps, and learning first buys it steps).
// The presets' reward weights: `small` tracks with less style reward (README, Performance,
// "Learning": the walk's 30-export medians), `paper` keeps PHC's 0.5 / 0.5.
TEST(LearnerTrainingTest, PresetsWeighStyleAndTaskRewards) {
  const TrainerConfig small = *TrainerConfig::ForPreset("small"), paper = *TrainerConfig::ForPreset("paper");
  EXPECT_DOUBLE_EQ(small.amp_reward_weight, 0.2);
  EXPECT_DOUBLE_EQ(small.task_reward_weight, 0.8);
  EXPECT_DOUBLE_EQ(paper.amp_reward_weight, 0.5);
  EXPECT_DOUBLE_EQ(paper.task_reward_weight, 0.5);
}

TEST(LearnerTrainingTest, ReturnRisesOnASingleClip) {
  // One fixed clip: generated variants joining mid-run would change what the return measures.
  ServerOptions options;
  options.service.generation.enabled = false;
  auto server = StartTestServer(options);
  TrainerConfig config = SingleClipConfig(server->port(), RunDir("learn"));
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok());
  ASSERT_TRUE((*trainer)->Run().ok());
  const auto& history = (*trainer)->history();
  auto mean_return = [&](size_t begin, size_t end) { return MeanReturn(history, begin, end); };
  const size_t n = history.size();
  EXPECT_GT(mean_return(n - 3, n), 1.1 * mean_return(0, 3))
      << "first " << mean_return(0, 3) << " last " << mean_return(n - 3, n);
  std::printf("mean episode return: first 3 iterations %.3f, last 3 %.3f\n", mean_return(0, 3), mean_return(n - 3, n));
  server->Shutdown(absl::Seconds(1));
}

// A seed fixes a run: two runs with one seed against servers on different ports collect and learn
// the same figures, and another seed does not. (Envs' seeds once mixed in the server's address,
// and the bench's servers take whatever port is free.)
TEST(LearnerTrainingTest, ASeedFixesTheRunWhateverPortItsServerListensOn) {
  ServerOptions options;
  options.service.generation.enabled = false;  // generated clips join when they are ready, not at a step
  auto first = StartTestServer(options), second = StartTestServer(options), third = StartTestServer(options);
  ASSERT_NE(first->port(), second->port());
  auto train = [](int port, uint64_t seed, const std::string& name) {
    TrainerConfig config = SingleClipConfig(port, RunDir(name));
    config.iterations = 2;
    config.seed = seed;
    auto trainer = Trainer::Create(config);
    EXPECT_TRUE(trainer.ok()) << trainer.status();
    if (!trainer.ok()) return std::vector<IterationStats>{};
    EXPECT_TRUE((*trainer)->Run().ok());
    return (*trainer)->history();
  };
  const std::vector<IterationStats> run = train(first->port(), 5, "seed_first"),
                                    again = train(second->port(), 5, "seed_second"),
                                    other_seed = train(third->port(), 6, "seed_other");
  ASSERT_EQ(run.size(), 2u);
  ASSERT_EQ(again.size(), 2u);
  ASSERT_EQ(other_seed.size(), 2u);
  for (size_t i = 0; i < run.size(); ++i) {
    EXPECT_EQ(run[i].mean_task_reward, again[i].mean_task_reward) << "iteration " << i + 1;
    EXPECT_EQ(run[i].mean_episode_length, again[i].mean_episode_length) << "iteration " << i + 1;
    EXPECT_EQ(run[i].policy_loss, again[i].policy_loss) << "iteration " << i + 1;
    EXPECT_EQ(run[i].discriminator_loss, again[i].discriminator_loss) << "iteration " << i + 1;
  }
  EXPECT_NE(run[0].mean_task_reward, other_seed[0].mean_task_reward);
  for (auto* server : {&first, &second, &third}) (*server)->Shutdown(absl::Seconds(1));
}

// --keep_best_every: each due iteration's policy is evaluated, the best so far is the file kept
// (it scores again exactly what it scored), a resume re-scores it, and a fresh run drops it.
TEST(LearnerTrainingTest, KeepsTheBestEvaluatedPolicyAcrossAResume) {
  ServerOptions options;
  options.service.generation.enabled = false;
  auto server = StartTestServer(options);
  auto client = ConnectTo(*server);
  const std::string dir = RunDir("keep_best");
  TrainerConfig config = SingleClipConfig(server->port(), dir);
  config.iterations = 4;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  EXPECT_FALSE(BestPolicyKeeper::Create(**trainer, client.get(), 0).ok());
  auto keeper = BestPolicyKeeper::Create(**trainer, client.get(), 2);
  ASSERT_TRUE(keeper.ok()) << keeper.status();
  absl::Status kept;
  ASSERT_TRUE((*trainer)->Run([&](const IterationStats&) { kept.Update((*keeper)->AfterIteration(**trainer)); }).ok());
  ASSERT_TRUE(kept.ok()) << kept;
  const std::vector<PolicyScore>& scores = (*keeper)->scores();
  ASSERT_EQ(scores.size(), 2u);  // iterations 2 and 4
  EXPECT_EQ(scores[0].iteration, 2);
  EXPECT_EQ(scores[1].iteration, 4);
  ASSERT_TRUE((*keeper)->best().has_value());
  const PolicyScore best = *(*keeper)->best();
  for (const PolicyScore& score : scores) EXPECT_FALSE(score.BetterThan(best)) << "iteration " << score.iteration;
  EXPECT_FALSE(std::filesystem::exists(dir + "/policy_candidate.pt"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/policy_best.md"));
  auto lines_of_curve = [&dir] {
    std::vector<std::string> lines;
    std::ifstream in(dir + "/evaluations.csv");
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  };
  const std::vector<std::string> curve = lines_of_curve();
  ASSERT_EQ(curve.size(), 3u);  // the header and one row per evaluation
  EXPECT_EQ(curve[0], "iteration,env_steps,success_rate,mpjpe_mm,g_mpjpe_mm,kept");
  EXPECT_THAT(curve[1], ::testing::StartsWith("2,"));
  EXPECT_THAT(curve[1], ::testing::EndsWith(",1"));  // the first evaluation is the best so far
  auto again = Evaluate(*client, "policy_best.pt", *ReadFileToString(dir + "/policy_best.pt", 1 << 30), config.motions);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->mpjpe_mm, best.mpjpe_mm);
  EXPECT_EQ(again->g_mpjpe_mm, best.g_mpjpe_mm);

  ASSERT_TRUE((*trainer)->SaveCheckpoint(dir + "/checkpoint.pt").ok());
  config.resume = true;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  auto rescored = BestPolicyKeeper::Create(**resumed, client.get(), 2);
  ASSERT_TRUE(rescored.ok()) << rescored.status();
  ASSERT_TRUE((*rescored)->best().has_value());
  EXPECT_EQ((*rescored)->best()->mpjpe_mm, best.mpjpe_mm);
  EXPECT_EQ(lines_of_curve().size(), 3u) << "a resume continues the curve";

  config.resume = false;
  auto fresh = Trainer::Create(config);
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  auto fresh_keeper = BestPolicyKeeper::Create(**fresh, client.get(), 2);
  ASSERT_TRUE(fresh_keeper.ok()) << fresh_keeper.status();
  EXPECT_FALSE((*fresh_keeper)->best().has_value());
  EXPECT_FALSE(std::filesystem::exists(dir + "/policy_best.pt"));
  EXPECT_EQ(lines_of_curve().size(), 1u) << "a fresh run starts its own curve";
  server->Shutdown(absl::Seconds(1));
}

// Collection during the update acts with the weights from before it: a lag of one update from
// the second iteration on, every step counted once, and the return still rises.
TEST(LearnerTrainingTest, CollectingDuringTheUpdateLagsByOneUpdateAndLearns) {
  ServerOptions options;
  options.service.generation.enabled = false;
  auto server = StartTestServer(options);
  TrainerConfig config = SingleClipConfig(server->port(), RunDir("during_update"));
  config.collect_during_update = true;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok());
  ASSERT_TRUE((*trainer)->Run().ok());
  const auto& history = (*trainer)->history();
  ASSERT_EQ(history.size(), 12u);
  EXPECT_EQ(history[0].policy_lag, 0);
  for (size_t i = 1; i < history.size(); ++i) EXPECT_EQ(history[i].policy_lag, 1) << "iteration " << i + 1;
  EXPECT_EQ((*trainer)->env_steps(), 12 * 64 * 16);
  auto mean_return = [&](size_t begin, size_t end) { return MeanReturn(history, begin, end); };
  // Slower than without lag at this tiny batch (1,024 steps; measured 1.21 -> 1.29 over 12
  // iterations against 1.20 -> 1.50 sequentially; first and last three 1.21 and 1.26).
  const size_t n = history.size();
  EXPECT_GT(mean_return(n - 3, n), 1.03 * mean_return(0, 3))
      << "first " << mean_return(0, 3) << " last " << mean_return(n - 3, n);
  std::printf("mean episode return with a lag of one update: first 3 iterations %.3f, last 3 %.3f\n",
              mean_return(0, 3), mean_return(n - 3, n));
  // The next run starts with no collection left over: a second Run continues cleanly.
  ASSERT_TRUE((*trainer)->Run().ok());
  EXPECT_EQ((*trainer)->iteration(), 24);
  server->Shutdown(absl::Seconds(1));
}

// A task run's exported policy still holds the tracker's skills: the same controller weights and,
// at every body's self features, the tracker's observation statistics.
void ExpectSkillsIntact(const std::string& skills_path, const std::string& policy_path, const v1::EnvSpec& tracking,
                        const v1::EnvSpec& task) {
  auto library = SkillLibrary::Load(skills_path);
  ASSERT_TRUE(library.ok()) << library.status();
  auto imported = ImportTaskPolicy(policy_path, task);
  ASSERT_TRUE(imported.ok()) << imported.status();
  EXPECT_TRUE(library->CheckSameControllers(*imported->policy).ok()) << "the skills changed in training";
  RunningMeanStd tracker_statistics(task.obs_size());
  ASSERT_TRUE(library->LoadSelfStatistics(tracking, task, *tracker_statistics).ok());
  const torch::Tensor self = tracker_statistics->frozen();
  EXPECT_TRUE(torch::equal(imported->obs_norm->mean().masked_select(self), tracker_statistics->mean().masked_select(self)));
  EXPECT_TRUE(torch::equal(imported->obs_norm->var().masked_select(self), tracker_statistics->var().masked_select(self)));
}

// Skill reuse end to end: a proprioceptive tracker's policy.pt drives a steer run whose task
// policy trains, exports with the skills unchanged inside, resumes, and is evaluated beside the
// random-z and constant-z baselines; an unknown task is refused before any session opens.
TEST(LearnerTrainingTest, SteerPolicyTrainsOverATrackersFrozenSkills) {
  auto server = StartTestServer();
  auto trained_skills = TrainWalkSkills({absl::StrCat("127.0.0.1:", server->port())}, RunDir("skills_tracker"));
  ASSERT_TRUE(trained_skills.ok()) << trained_skills.status();
  const std::string skills = *trained_skills;

  const std::string dir = RunDir("steer");
  TrainerConfig config = SmallConfig({server->port()}, dir);
  config.motions = {"deepmimic_walk"};
  config.task = "steer";
  config.skills = skills;
  config.report_every = 1;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  EXPECT_EQ((*trainer)->spec().task(), "steer");
  EXPECT_EQ((*trainer)->policy()->sample_size(), 5 * 32);
  ASSERT_TRUE((*trainer)->Run().ok());
  EXPECT_EQ((*trainer)->iteration(), 2);
  EXPECT_TRUE(std::isfinite((*trainer)->history().back().policy_loss));
  // The training reward is the server's: speed + facing + energy (the paper's penalty, negative).
  const IterationStats& paid = (*trainer)->history().back();
  EXPECT_LT(paid.reward_terms[2], 0.0) << "energy";
  EXPECT_NEAR(paid.mean_task_reward, paid.reward_terms[0] + paid.reward_terms[1] + paid.reward_terms[2], 1e-5);
  auto client = ConnectTo(*server);
  EXPECT_EQ(client->GetStats()->failure_reports(), 0) << "steer episodes follow no clip";

  auto tracking = client->Describe("5part");
  ASSERT_TRUE(tracking.ok()) << tracking.status();
  ExpectSkillsIntact(skills, dir + "/policy.pt", *tracking, (*trainer)->spec());

  config.resume = true;
  config.iterations = 1;
  config.energy_weight = 0;  // the resumed part's sessions have no penalty: no step is negative
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_TRUE((*resumed)->Run().ok());
  EXPECT_EQ((*resumed)->iteration(), 3);
  const IterationStats& unpaid = (*resumed)->history().back();
  EXPECT_EQ(unpaid.reward_terms[2], 0.0) << "the server's energy column, weighted 0";
  EXPECT_NEAR(unpaid.mean_task_reward, unpaid.reward_terms[0] + unpaid.reward_terms[1], 1e-5);
  ExpectSkillsIntact(skills, dir + "/policy.pt", *tracking, (*trainer)->spec());
  auto imported = ImportTaskPolicy(dir + "/policy.pt", (*trainer)->spec());
  ASSERT_TRUE(imported.ok()) << imported.status();

  TaskEvaluationOptions options = SmallTaskEvaluation("steer", config, 30);
  auto report = EvaluateTaskPolicy(*client, *imported, "steer policy", options);
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_EQ(report->rows.size(), 4u) << "the policy, random z, constant z and the skill prior alone";
  for (const TaskEvaluationRow& row : report->rows) {
    EXPECT_EQ(row.episodes, 4) << row.z_source;
    EXPECT_GE(row.mean_normalized_return, 0.0) << row.z_source;
    EXPECT_LE(row.mean_normalized_return, 1.0) << row.z_source;
    EXPECT_LE(row.mean_episode_length, 30.0) << row.z_source;
    // Every episode says why it ended: the 30-step limit or a fall, nothing unreported.
    EXPECT_EQ(row.ends.total(), 4) << row.z_source;
    EXPECT_EQ(row.ends.count(v1::END_CAUSE_TIME) + row.ends.count(v1::END_CAUSE_FALL), 4) << row.z_source;
    // Steer's goal terms split the return; the energy column is no part of it.
    ASSERT_EQ(row.by_term.size(), 2u) << row.z_source;
    EXPECT_EQ(row.by_term[0].first, "speed");
    EXPECT_EQ(row.by_term[1].first, "facing");
    EXPECT_NEAR(row.by_term[0].second + row.by_term[1].second, row.mean_normalized_return, 1e-6) << row.z_source;
    EXPECT_GT(row.by_term[0].second, 0.0) << row.z_source;
  }
  EXPECT_THAT(report->ToMarkdown(), HasSubstr("| by term |"));
  EXPECT_THAT(report->ToMarkdown(), HasSubstr("speed 0."));
  EXPECT_THAT(report->ToJson(), HasSubstr("\"by_term\""));
  EXPECT_THAT(report->ToMarkdown(), HasSubstr("| ended by |"));
  EXPECT_THAT(report->ToJson(), HasSubstr("\"ended_by\""));
  EXPECT_THAT(report->ToMarkdown(), HasSubstr("random unit z"));
  EXPECT_THAT(report->ToMarkdown(), HasSubstr("skill prior alone"));

  TrainerConfig unknown = config;
  unknown.task = "juggle";
  unknown.resume = false;
  auto refused = Trainer::Create(unknown);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("--task juggle"));
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("steer"));

  // --task_parts R_Arm: the exported head leaves every other part's z on the prior.
  TrainerConfig arm = config;
  arm.run_dir = RunDir("steer_arm");
  arm.resume = false;
  arm.iterations = 2;
  arm.task_parts = {"R_Arm"};
  auto arm_trainer = Trainer::Create(arm);
  ASSERT_TRUE(arm_trainer.ok()) << arm_trainer.status();
  ASSERT_TRUE((*arm_trainer)->Run().ok());
  auto arm_policy = ReadExportedPolicy(arm.run_dir + "/policy.pt");
  ASSERT_TRUE(arm_policy.ok()) << arm_policy.status();
  const torch::Tensor& last_bias = arm_policy->tensors.at("task_head_fc2_bias");  // [5 parts * 32]
  EXPECT_EQ(last_bias.slice(0, 0, 4 * 32).abs().max().item<double>(), 0.0) << "a part outside --task_parts moved";
  EXPECT_GT(last_bias.slice(0, 4 * 32).abs().max().item<double>(), 0.0) << "the arm's head did not learn";
  server->Shutdown(absl::Seconds(1));
}

}  // namespace
}  // namespace modskill::learner
