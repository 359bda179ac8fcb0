// Retraining some parts of a tracker (issue 13 item 4, learner/part_retraining.h): from the shipped
// walk tracker, only the arms train on the punch; every other part's controller and attention maps
// and the observation statistics come out of training bit for bit as they went in, the arms'
// do not; bad --init_from and --train_parts are named.
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include <gmock/gmock.h>

#include "common/atomic_file.h"
#include "learner/part_retraining.h"
#include "learner/policy_import.h"
#include "learner/trainer.h"
#include "tests/env_specs.h"
#include "tests/server_fixture.h"
#include "tests/trainer_test_config.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;

const std::string kWalkTracker = std::string(MODSKILL_REPO_DIR) + "/data/policies/walk_small/policy.pt";

TrainerConfig RetrainArms(const RunningServer& server, const std::string& name) {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/part_retraining/" + name;
  std::filesystem::remove_all(dir);
  TrainerConfig config = SmallTestTrainerConfig({absl::StrCat("127.0.0.1:", server.port())}, dir);
  config.motions = {"deepmimic_punch"};
  config.init_from = kWalkTracker;
  config.train_parts = {"R_Arm", "L_Arm"};
  return config;
}

// Whether every tensor of `prefix` (part<p>_controller, part<p>_key, ...) is the same in both files.
bool SameTensors(const ExportedPolicy& a, const ExportedPolicy& b, const std::string& prefix) {
  int compared = 0;
  for (const auto& [name, tensor] : a.tensors) {
    if (name.rfind(prefix, 0) != 0) continue;
    if (!b.Has(name) || !torch::equal(tensor, b.tensors.at(name))) return false;
    ++compared;
  }
  EXPECT_GT(compared, 0) << prefix;
  return compared > 0;
}

bool IsArm(const std::string& part) { return part == "R_Arm" || part == "L_Arm"; }

// For each part of `env` and each of `roles`: the tensors are the tracker's exactly when
// `unchanged(part)` says so.
void ExpectUnchanged(const ExportedPolicy& before, const ExportedPolicy& after, const v1::EnvSpec& env,
                     std::initializer_list<const char*> roles, const std::function<bool(const std::string&)>& unchanged) {
  for (int p = 0; p < env.parts_size(); ++p) {
    for (const char* role : roles) {
      EXPECT_EQ(SameTensors(before, after, absl::StrCat("part", p, "_", role)), unchanged(env.parts(p).name()))
          << env.parts(p).name() << " " << role;
    }
  }
}

// The tracker before and the policy `config` trained, and the server's spec, once the run has
// ended and every part but the arms came out as the tracker's.
struct ArmsRetrained {
  ExportedPolicy before, after;
  v1::EnvSpec env;
};

std::optional<ArmsRetrained> TrainOnlyTheArms(const RunningServer& server, const TrainerConfig& config) {
  auto trainer = Trainer::Create(config);
  EXPECT_TRUE(trainer.ok()) << trainer.status();
  if (!trainer.ok() || !(*trainer)->Run().ok()) return std::nullopt;
  auto before = ReadExportedPolicy(kWalkTracker);
  auto after = ReadExportedPolicy(config.run_dir + "/policy.pt");
  // 5part: L_Leg, R_Leg, Torso, L_Arm, R_Arm (the server's order).
  auto env = ConnectTo(server)->Describe();
  if (!before.ok() || !after.ok() || !env.ok()) return std::nullopt;
  ExpectUnchanged(*before, *after, *env, {"controller", "key", "query", "value"},
                  [](const std::string& part) { return !IsArm(part); });
  return ArmsRetrained{*std::move(before), *std::move(after), *std::move(env)};
}

TEST(PartRetrainingTest, OnlyTheNamedPartsTrain) {
  auto server = StartTestServer();
  TrainerConfig config = RetrainArms(*server, "arms");
  // Shapes unlike the tracker's (small: attention {64} -> 32, controllers {256, 128}): the
  // tracker's networks are built, and config.json and the checkpoint say so.
  config.model.attention_hidden = {16};
  config.model.embed_dim = 8;
  config.model.controller_hidden = {48, 24};
  std::optional<ArmsRetrained> run = TrainOnlyTheArms(*server, config);
  ASSERT_TRUE(run.has_value());
  const ExportedPolicy& before = run->before;
  const ExportedPolicy& after = run->after;
  const v1::EnvSpec& env = run->env;
  EXPECT_TRUE(torch::equal(before.tensors.at("obs_mean"), after.tensors.at("obs_mean")));
  EXPECT_TRUE(torch::equal(before.tensors.at("obs_var"), after.tensors.at("obs_var")));

  // Resumed, the frozen parts stay frozen.
  config.resume = true;
  config.iterations = 1;
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  const ModelConfig& built = (*resumed)->config().model;
  EXPECT_EQ(built.embed_dim, 32);
  EXPECT_EQ(built.attention_hidden, std::vector<int64_t>({64}));
  EXPECT_EQ(built.controller_hidden, std::vector<int64_t>({256, 128}));
  auto recorded = ReadFileToString(config.run_dir + "/config.json", 1 << 20);
  ASSERT_TRUE(recorded.ok());
  EXPECT_THAT(*recorded, HasSubstr("\"embed_dim\": 32"));
  ASSERT_TRUE((*resumed)->Run().ok());
  auto again = ReadExportedPolicy(config.run_dir + "/policy.pt");
  ASSERT_TRUE(again.ok());
  for (int p = 0; p < env.parts_size(); ++p) {
    const std::string prefix = absl::StrCat("part", p, "_controller");
    if (env.parts(p).name() == "R_Arm") {
      EXPECT_FALSE(SameTensors(after, *again, prefix));
    } else if (env.parts(p).name() != "L_Arm") {
      EXPECT_TRUE(SameTensors(before, *again, prefix));
    }
  }
}

// With --train_attention=false the arms' controllers train alone: every attention map is the
// tracker's, so every part's z is too.
TEST(PartRetrainingTest, ControllersAloneKeepEveryAttentionMap) {
  auto server = StartTestServer();
  TrainerConfig config = RetrainArms(*server, "controllers");
  config.train_attention = false;
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run().ok());
  auto before = ReadExportedPolicy(kWalkTracker);
  auto after = ReadExportedPolicy(config.run_dir + "/policy.pt");
  ASSERT_TRUE(before.ok() && after.ok());
  auto env = ConnectTo(*server)->Describe();
  ASSERT_TRUE(env.ok());
  ExpectUnchanged(*before, *after, *env, {"controller"}, [](const std::string& part) { return !IsArm(part); });
  ExpectUnchanged(*before, *after, *env, {"key", "query", "value"}, [](const std::string&) { return true; });
  TrainerConfig everything = RetrainArms(*server, "bad");
  everything.train_parts.clear();
  everything.train_attention = false;
  EXPECT_THAT(std::string(Trainer::Create(everything).status().message()), HasSubstr("--train_attention"));
}

// The arms rewarded for their own bodies and the frozen parts acting on their means: the arms
// still train and everything else stays the tracker's.
TEST(PartRetrainingTest, ArmsRewardedAndExploringAlone) {
  auto server = StartTestServer();
  TrainerConfig config = RetrainArms(*server, "arms_alone");
  config.reward_parts = {"R_Arm", "L_Arm"};
  config.frozen_parts_act_on_mean = true;
  EXPECT_TRUE(TrainOnlyTheArms(*server, config).has_value());
}

// With --fresh_parts the arms start as a part new to the tracker: their controllers and attention
// maps take the initial weights a fresh policy gets, every other part stays the tracker's, and
// only the arms train.
TEST(PartRetrainingTest, FreshPartsTakeAFreshPolicysInitialWeights) {
  const NetworkLayout layout = LayoutFromWireSpec(SpecsOf("5part").wire);
  auto exported = ReadExportedPolicy(kWalkTracker);
  ASSERT_TRUE(exported.ok()) << exported.status();
  const ActionMapping action = exported->spec.action;
  const std::vector<std::string> arms = {"R_Arm", "L_Arm"};
  auto kept = LoadTrackerForRetraining(kWalkTracker, arms, "5part", layout, action);
  ASSERT_TRUE(kept.ok()) << kept.status();
  torch::manual_seed(11);
  auto fresh = LoadTrackerForRetraining(kWalkTracker, arms, "5part", layout, action, true, /*fresh_parts=*/true);
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  // The same draws as the load above: the tracker's rebuilt policy, then the fresh one.
  torch::manual_seed(11);
  const ModSkillPolicy rebuilt(layout, kept->policy->config()), initial(layout, kept->policy->config());

  const auto modules = [](const ModSkillPolicyImpl& policy, int p) -> std::vector<const torch::nn::Module*> {
    const SkillAttentionImpl& attention = *policy.attention();
    return {policy.controllers()[p].get(), attention.values()[p].get(), attention.keys()[p].get(),
            attention.queries()[p].get()};
  };
  const auto same = [](const torch::nn::Module& a, const torch::nn::Module& b) {
    const std::vector<torch::Tensor> x = a.parameters(), y = b.parameters();
    for (size_t i = 0; i < x.size(); ++i) {
      if (!torch::equal(x[i], y[i])) return false;
    }
    return !x.empty() && x.size() == y.size();
  };
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    const bool arm = IsArm(layout.parts[p].name);
    const std::vector<const torch::nn::Module*> got = modules(*fresh->policy, p), tracker = modules(*kept->policy, p),
                                                fresh_start = modules(*initial, p);
    for (size_t m = 0; m < got.size(); ++m) {
      EXPECT_EQ(same(*got[m], *tracker[m]), !arm) << layout.parts[p].name << " module " << m;
      EXPECT_EQ(same(*got[m], *fresh_start[m]), arm) << layout.parts[p].name << " module " << m;
      for (const torch::Tensor& w : got[m]->parameters()) EXPECT_EQ(w.requires_grad(), arm) << layout.parts[p].name;
    }
  }
  EXPECT_TRUE(torch::equal(fresh->obs_norm->mean(), kept->obs_norm->mean()));
}

// Resumed, fresh parts continue from the checkpoint's weights, not from fresh ones again.
TEST(PartRetrainingTest, FreshPartsResumeFromTheCheckpoint) {
  auto server = StartTestServer();
  TrainerConfig config = RetrainArms(*server, "fresh_resume");
  config.fresh_parts = true;
  std::optional<ArmsRetrained> run = TrainOnlyTheArms(*server, config);
  ASSERT_TRUE(run.has_value());
  config.resume = true;
  config.iterations = 0;  // as far as the first run went: nothing trains
  auto resumed = Trainer::Create(config);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_TRUE((*resumed)->Run().ok());
  auto again = ReadExportedPolicy(config.run_dir + "/policy.pt");
  ASSERT_TRUE(again.ok()) << again.status();
  ExpectUnchanged(run->after, *again, run->env, {"controller", "key", "query", "value"},
                  [](const std::string&) { return true; });
}

TEST(PartRetrainingTest, BadSettingsAreNamed) {
  auto server = StartTestServer();
  TrainerConfig unknown = RetrainArms(*server, "bad");
  unknown.train_parts = {"R_Arm", "Tail"};
  auto refused = Trainer::Create(unknown);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("--train_parts[1]: 'Tail'"));

  TrainerConfig twice = RetrainArms(*server, "bad");
  twice.train_parts = {"R_Arm", "R_Arm"};
  EXPECT_THAT(std::string(Trainer::Create(twice).status().message()), HasSubstr("given twice"));

  TrainerConfig absolute = RetrainArms(*server, "bad");
  absolute.action_mode = "absolute";
  auto mode = Trainer::Create(absolute);
  EXPECT_EQ(mode.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(mode.status().message()), HasSubstr("--init_from"));

  TrainerConfig missing = RetrainArms(*server, "bad");
  missing.init_from = "/nonexistent/policy.pt";
  EXPECT_THAT(std::string(Trainer::Create(missing).status().message()), HasSubstr("--init_from"));

  TrainerConfig no_tracker = RetrainArms(*server, "bad");
  no_tracker.init_from.clear();
  auto needs = Trainer::Create(no_tracker);
  EXPECT_EQ(needs.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(needs.status().message()), HasSubstr("--train_parts: needs --init_from"));

  TrainerConfig on_mean = RetrainArms(*server, "bad");
  on_mean.train_parts.clear();
  on_mean.frozen_parts_act_on_mean = true;
  EXPECT_THAT(std::string(Trainer::Create(on_mean).status().message()),
              HasSubstr("--frozen_parts_act_on_mean: only with --train_parts"));

  TrainerConfig fresh_everything = RetrainArms(*server, "bad");
  fresh_everything.train_parts.clear();
  fresh_everything.fresh_parts = true;
  EXPECT_THAT(std::string(Trainer::Create(fresh_everything).status().message()),
              HasSubstr("--fresh_parts: only with --train_parts"));

  // The reward's settings are tracking's: a task run refuses them before any session opens.
  TrainerConfig steer = RetrainArms(*server, "bad");
  steer.init_from.clear();
  steer.train_parts.clear();
  steer.frozen_parts_act_on_mean = false;
  steer.task = "steer";
  steer.skills = "skills/policy.pt";
  steer.reward_relative_to_root = true;
  EXPECT_THAT(std::string(Trainer::Create(steer).status().message()),
              HasSubstr("--reward_relative_to_root: tracking only, not with --task steer"));
  steer.reward_parts = {"R_Arm"};
  EXPECT_THAT(std::string(Trainer::Create(steer).status().message()),
              HasSubstr("--reward_parts: tracking only, not with --task steer"));
  steer.reward_parts.clear();
  steer.reward_relative_to_root = false;
  steer.anchor_reference = true;  // a task anchors its base motion itself
  EXPECT_THAT(std::string(Trainer::Create(steer).status().message()),
              HasSubstr("--anchor_reference: tracking only, not with --task steer"));
  steer.task = "tracking";
  steer.skills.clear();
  steer.anchor_reference = false;
  steer.anchor_position_only = true;
  EXPECT_THAT(std::string(Trainer::Create(steer).status().message()),
              HasSubstr("--anchor_position_only: only with --anchor_reference"));

  // An unknown reward part is the server's refusal, named, at once (not after --server_timeout_s).
  TrainerConfig tail = RetrainArms(*server, "bad");
  tail.reward_parts = {"Tail"};
  const absl::Time start = absl::Now();
  auto tail_trainer = Trainer::Create(tail);
  ASSERT_FALSE(tail_trainer.ok());
  EXPECT_EQ(tail_trainer.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(tail_trainer.status().message()), HasSubstr("reward_parts[0]: 'Tail'"));
  EXPECT_LT(absl::Now() - start, absl::Seconds(tail.server_timeout_s / 2));
}

}  // namespace
}  // namespace modskill::learner
