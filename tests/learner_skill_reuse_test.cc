// Skill reuse on the learner's side (issue 13), without a server: the task layout, the skills read
// from a tracker's exported policy.pt (and the files refused as skills), the task policy over the
// frozen controllers, PPO updates that leave the controllers and the tracker's normalizer dims
// alone, and the exported task policy. Specs are the server's, as Describe and a task session
// send them.
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/script.h>
#include <torch/torch.h>

#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/tensor_codec.h"
#include "learner/critic.h"
#include "learner/episode_ends.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/policy_export.h"
#include "learner/policy_import.h"
#include "learner/ppo_update.h"
#include "learner/reach_teacher.h"
#include "learner/running_mean_std.h"
#include "learner/skill_library.h"
#include "learner/task_evaluation.h"
#include "learner/task_parts.h"
#include "learner/task_return.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/policy_fit.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/core/sim/physics_options.h"
#include "server/service/proto_conversions.h"
#include "tests/env_specs.h"
#include "tests/test_files.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;


const v1::EnvSpec& Tracking(const std::string& layout = "5part") { return SpecsOf(layout).wire; }
const v1::EnvSpec& Steer(const std::string& layout = "5part") { return SpecsOf(layout, TaskKind::kSteer).wire; }

ModelConfig SmallConfig() { return *ModelConfig::Preset("small"); }

// Steer observes tracking's 934 features (its anchored base motion as the reference), then a
// goal of 3.
constexpr int64_t kSteerGoalStart = 934, kSteerObs = 937;

std::string TmpPath(const std::string& name) {
  return ProcessTempDir("skill_reuse") + "/" + name;
}

// Statistics as after training: far from mean 0, var 1.
RunningMeanStd TrainedNormalizer(int64_t size) {
  RunningMeanStd norm(size);
  for (int i = 0; i < 3; ++i) norm->Update(torch::randn({64, size}) * 3.0 + torch::linspace(-2, 2, size));
  return norm;
}

// A tracker's exported policy.pt with `input` controllers; `record_input` false writes the spec
// as files from before PolicySpec recorded controller_input did.
std::string ExportTracker(const std::string& name, const std::string& layout_name = "5part",
                          ModelConfig::ControllerInput input = ModelConfig::ControllerInput::kProprioception,
                          bool record_input = true) {
  ModelConfig config = SmallConfig();
  config.controller_input = input;
  ModSkillPolicy tracker(LayoutFromWireSpec(Tracking(layout_name)), config);
  RunningMeanStd norm = TrainedNormalizer(Tracking(layout_name).obs_size());
  PolicySpec spec = PolicySpecForEnv(SpecsOf(layout_name).env);
  if (record_input) spec.controller_input = ControllerInputName(input);
  const std::string path = TmpPath(name);
  const absl::Status exported = ExportPolicy(tracker, norm, spec, path);
  EXPECT_TRUE(exported.ok()) << exported;
  return path;
}

const SkillLibrary& Skills() {
  static const SkillLibrary* skills = [] {
    auto loaded = SkillLibrary::Load(ExportTracker("skill_reuse_tracker.pt"));
    EXPECT_TRUE(loaded.ok()) << loaded.status();
    return new SkillLibrary(*std::move(loaded));
  }();
  return *skills;
}

// A steer policy over the skills' frozen controllers, and its normalizer.
struct TaskNetworks {
  ModSkillPolicy policy{nullptr};
  RunningMeanStd norm{nullptr};
};

TaskNetworks SteerNetworks() {
  TaskNetworks made;
  made.policy = ModSkillPolicy(LayoutFromWireSpec(Steer()), Skills().ConfigFor(SmallConfig()));
  made.norm = RunningMeanStd(Steer().obs_size());
  EXPECT_TRUE(Skills().LoadControllers(*made.policy).ok());
  EXPECT_TRUE(Skills().LoadSelfStatistics(Tracking(), Steer(), *made.norm).ok());
  return made;
}

std::vector<torch::Tensor> Clones(const std::vector<torch::Tensor>& tensors) {
  std::vector<torch::Tensor> clones;
  for (const torch::Tensor& t : tensors) clones.push_back(t.detach().clone());
  return clones;
}

bool AllEqual(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!torch::equal(a[i], b[i])) return false;
  }
  return true;
}

TEST(SkillReuseTest, TaskLayoutHasTheGoalAfterThePartsFeatures) {
  const NetworkLayout layout = LayoutFromWireSpec(Steer());
  EXPECT_EQ(layout.task, "steer");
  EXPECT_TRUE(layout.has_goal());
  EXPECT_EQ(layout.goal_start, kSteerGoalStart);
  EXPECT_EQ(layout.goal_size, 3);
  EXPECT_EQ(layout.obs_size, kSteerObs);
  EXPECT_EQ(layout.parts_obs_end(), kSteerGoalStart);
  EXPECT_TRUE(layout.Validate().ok()) << layout.Validate();
  const NetworkLayout tracking = LayoutFromWireSpec(Tracking());
  EXPECT_EQ(tracking.task, "tracking");
  EXPECT_FALSE(tracking.has_goal());
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    EXPECT_EQ(layout.parts[p].obs_start, tracking.parts[p].obs_start) << layout.parts[p].name;
    EXPECT_EQ(layout.parts[p].obs_size, tracking.parts[p].obs_size) << layout.parts[p].name;
  }
  // VR tracking observes its three bodies in the goal only: the parts hold their self features.
  const NetworkLayout vr = LayoutFromWireSpec(SpecsOf("5part", TaskKind::kVrTracking).wire);
  EXPECT_EQ(vr.goal_start, 358);
  for (const PartSlices& part : vr.parts) EXPECT_EQ(part.self_obs_size(), part.obs_size) << part.name;

  NetworkLayout short_goal = layout;
  short_goal.goal_size = 2;
  EXPECT_THAT(std::string(short_goal.Validate().message()), HasSubstr("goal"));
  NetworkLayout overlapping = layout;
  overlapping.parts.back().obs_size += 1;  // into the goal
  EXPECT_THAT(std::string(overlapping.Validate().message()), HasSubstr("where the goal starts"));
}

// Tracking is unchanged: PPO samples the actions themselves.
TEST(SkillReuseTest, TrackingPolicySamplesItsActions) {
  torch::manual_seed(1);
  const NetworkLayout layout = LayoutFromWireSpec(Tracking());
  ModSkillPolicy policy(layout, SmallConfig());
  EXPECT_FALSE(policy->task_mode());
  EXPECT_EQ(policy->sample_size(), layout.action_size);
  EXPECT_EQ(policy->log_std().size(0), layout.action_size);
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({4, layout.obs_size});
  EXPECT_TRUE(torch::equal(policy->SampleMean(obs), policy->forward(obs)));
  const torch::Tensor sample = torch::randn({4, layout.action_size});
  EXPECT_TRUE(torch::equal(policy->ActionsFor(obs, sample), sample));
}

TEST(SkillReuseTest, SkillsComeFromAProprioceptiveTrackersExport) {
  const SkillLibrary& skills = Skills();
  EXPECT_EQ(skills.num_parts(), 5u);
  EXPECT_EQ(skills.embed_dim(), 32);
  EXPECT_EQ(skills.controller_hidden(), (std::vector<int64_t>{256, 128}));
  EXPECT_EQ(skills.spec().controller_input, "proprioception");
  const absl::Status fits = skills.CheckFits(Tracking(), Steer());
  EXPECT_TRUE(fits.ok()) << fits;
  // A proprioceptive tracker exported before the spec recorded controller_input is judged by its weights.
  auto unrecorded = SkillLibrary::Load(ExportTracker("skill_reuse_unrecorded.pt", "5part",
                                                     ModelConfig::ControllerInput::kProprioception, false));
  ASSERT_TRUE(unrecorded.ok()) << unrecorded.status();
  EXPECT_TRUE(unrecorded->CheckFits(Tracking(), Steer()).ok());
}

// (iii) What is refused as skills, each error naming the file.
TEST(SkillReuseTest, FilesThatAreNotReusableSkillsAreClearErrors) {
  const std::string garbage = TmpPath("skill_reuse_garbage.pt");
  ASSERT_TRUE(WriteFileAtomically(garbage, "not a zip archive").ok());
  auto not_policy = SkillLibrary::Load(garbage);
  EXPECT_EQ(not_policy.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(not_policy.status().message()), HasSubstr(garbage));
  EXPECT_THAT(std::string(not_policy.status().message()), HasSubstr("not a policy file"));

  const std::string affine = TmpPath("skill_reuse_affine.pt");
  ASSERT_TRUE(SaveAffinePolicy(affine, PolicySpecForEnv(SpecsOf("5part").env), {}, {}).ok());
  EXPECT_THAT(std::string(SkillLibrary::Load(affine).status().message()), HasSubstr("no part<p>_controller"));

  auto part_obs = SkillLibrary::Load(
      ExportTracker("skill_reuse_part_obs.pt", "5part", ModelConfig::ControllerInput::kPartObservation));
  ASSERT_TRUE(part_obs.ok()) << part_obs.status();
  const absl::Status reads_reference = part_obs->CheckFits(Tracking(), Steer());
  EXPECT_EQ(reads_reference.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(reads_reference.message()), HasSubstr("part_obs"));
  EXPECT_THAT(std::string(reads_reference.message()), HasSubstr("--controller_input proprioception"));
  EXPECT_THAT(std::string(reads_reference.message()), HasSubstr("skill_reuse_part_obs.pt"));

  auto three_parts = SkillLibrary::Load(ExportTracker("skill_reuse_3part.pt", "3part"));
  ASSERT_TRUE(three_parts.ok()) << three_parts.status();
  const absl::Status other_layout = three_parts->CheckFits(Tracking(), Steer());
  EXPECT_EQ(other_layout.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(other_layout.message()), HasSubstr("part layout 3part"));

  // A task policy is not a tracker.
  TaskNetworks steer = SteerNetworks();
  PolicySpec spec = PolicySpecForEnv(SpecsOf("5part", TaskKind::kSteer).env);
  spec.controller_input = "proprioception";
  const std::string task_policy = TmpPath("skill_reuse_steer_as_skills.pt");
  ASSERT_TRUE(ExportPolicy(steer.policy, steer.norm, spec, task_policy).ok());
  auto not_tracker = SkillLibrary::Load(task_policy);
  EXPECT_THAT(std::string(not_tracker.status().message()), HasSubstr("a policy for task steer"));
}

// Without the prior (--task_skill_prior=false), the paper's high level: z from the head alone.
TEST(SkillReuseTest, WithoutThePriorZComesFromTheHeadAlone) {
  torch::manual_seed(6);
  ModelConfig config = Skills().ConfigFor(SmallConfig());
  config.task_skill_prior = false;
  ModSkillPolicy policy(LayoutFromWireSpec(Steer()), config);
  ASSERT_TRUE(Skills().LoadControllers(*policy).ok());
  EXPECT_FALSE(policy->uses_skill_prior());
  EXPECT_TRUE(policy->attention().is_empty());
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({4, kSteerObs});
  Mlp task_head = policy->task_head();
  const torch::Tensor head = task_head->forward(obs).view({4, 5, 32});
  EXPECT_TRUE(torch::allclose(policy->skills(obs).z, head / head.norm(2, -1, true), 1e-6, 1e-6));
}

// With the prior, the tracker's frozen attention gives z on the base motion and the head's
// sample displaces it; a fresh head starts at (almost) the tracker's own z.
TEST(SkillReuseTest, ThePriorIsTheTrackersFrozenAttentionDisplacedByTheHead) {
  torch::manual_seed(7);
  TaskNetworks steer = SteerNetworks();
  ModSkillPolicyImpl& policy = *steer.policy;
  ASSERT_TRUE(policy.uses_skill_prior());
  auto tracker = ReadExportedPolicy(Skills().path());
  ASSERT_TRUE(tracker.ok()) << tracker.status();
  EXPECT_TRUE(torch::equal(policy.attention()->values()[2]->layers()[0]->weight, tracker->tensors.at("part2_value_fc0_weight")));
  EXPECT_TRUE(torch::equal(policy.attention()->keys()[4]->layers()[1]->bias, tracker->tensors.at("part4_key_fc1_bias")));
  for (const torch::Tensor& p : policy.attention()->parameters()) EXPECT_FALSE(p.requires_grad());
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({8, kSteerObs});
  SkillAttention attention = policy.attention();
  const torch::Tensor prior = attention->forward(obs).z;
  const torch::Tensor zero = torch::zeros({8, policy.sample_size()});
  EXPECT_TRUE(torch::allclose(policy.TaskZ(obs, zero), prior, 1e-6, 1e-6));
  EXPECT_GT((policy.skills(obs).z * prior).sum(-1).min().item<double>(), 0.99) << "a fresh head displaces z a little";
  const torch::Tensor sample = torch::randn({8, policy.sample_size()});
  const torch::Tensor displaced = prior + sample.view({8, 5, 32});
  EXPECT_TRUE(torch::allclose(policy.TaskZ(obs, sample), displaced / displaced.norm(2, -1, true), 1e-5, 1e-5));
  EXPECT_TRUE(torch::equal(policy.ActionsFor(obs, sample), policy.ControllerActions(obs, policy.TaskZ(obs, sample))));
}

TEST(SkillReuseTest, TaskPolicyDrivesTheTrackersControllersWithZFromItsHead) {
  torch::manual_seed(2);
  TaskNetworks steer = SteerNetworks();
  ModSkillPolicyImpl& policy = *steer.policy;
  EXPECT_TRUE(policy.task_mode());
  EXPECT_EQ(policy.sample_size(), 5 * 32);
  EXPECT_TRUE(torch::equal(policy.log_std(), torch::full({160}, -2.9)));
  EXPECT_TRUE(Skills().CheckSameControllers(policy).ok());
  for (const PartController& controller : policy.controllers()) {
    for (const torch::Tensor& p : controller->parameters()) EXPECT_FALSE(p.requires_grad());
  }
  for (const torch::Tensor& p : policy.task_head()->parameters()) EXPECT_TRUE(p.requires_grad());
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({6, kSteerObs});
  const torch::Tensor z = policy.skills(obs).z;
  EXPECT_TRUE(torch::allclose(z.norm(2, -1), torch::ones({6, 5}), 1e-5, 1e-5));
  EXPECT_TRUE(torch::equal(policy.forward(obs), policy.ActionsFor(obs, policy.SampleMean(obs))));
  // The goal reaches the actions only through z: with z fixed, the goal features change nothing.
  torch::Tensor other_goal = obs.clone();
  other_goal.slice(1, kSteerGoalStart, kSteerObs) += 3.0;
  EXPECT_TRUE(torch::equal(policy.ControllerActions(obs, z), policy.ControllerActions(other_goal, z)));
  EXPECT_FALSE(torch::equal(policy.forward(obs), policy.forward(other_goal)));
}

// (i) PPO updates move the task head and leave every controller weight as the skills had it.
TEST(SkillReuseTest, PpoUpdatesTrainTheTaskHeadAndLeaveTheSkillsFrozen) {
  torch::manual_seed(3);
  TaskNetworks steer = SteerNetworks();
  ModSkillPolicyImpl& policy = *steer.policy;
  Critic critic(kSteerObs, SmallConfig().critic_hidden);
  const std::vector<torch::Tensor> trainable = TrainableParameters(policy, *critic);
  EXPECT_EQ(trainable.size(), policy.task_head()->parameters().size() + critic->parameters().size());
  torch::optim::Adam optimizer(trainable, torch::optim::AdamOptions(1e-3));
  std::vector<torch::Tensor> controllers_before, head_before = Clones(policy.task_head()->parameters());
  const std::vector<torch::Tensor> attention_before = Clones(policy.attention()->parameters());
  for (const PartController& controller : policy.controllers()) {
    for (const torch::Tensor& p : Clones(controller->parameters())) controllers_before.push_back(p);
  }
  PpoSettings settings;
  settings.minibatch_size = 64;
  torch::Generator generator = at::detail::createCPUGenerator(3);
  int updates = 0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    PpoBatch batch;
    batch.obs = torch::randn({256, kSteerObs});
    torch::NoGradGuard no_grad;
    const torch::Tensor mean = policy.SampleMean(batch.obs);
    batch.samples = mean + policy.log_std().exp() * torch::randn(mean.sizes());
    batch.old_log_prob = ModSkillPolicyImpl::LogProb(mean, policy.log_std(), batch.samples);
    batch.old_values = critic->forward(batch.obs);
    batch.advantages = torch::randn({256});
    batch.returns = torch::randn({256});
    torch::AutoGradMode grad(true);
    updates += UpdateWithPpo(policy, *critic, optimizer, batch, settings, generator).updates;
  }
  EXPECT_EQ(updates, 3 * 2 * 4);
  std::vector<torch::Tensor> controllers_after;
  for (const PartController& controller : policy.controllers()) {
    for (const torch::Tensor& p : controller->parameters()) controllers_after.push_back(p);
  }
  EXPECT_TRUE(AllEqual(controllers_before, controllers_after)) << "the skills moved";
  EXPECT_TRUE(AllEqual(attention_before, policy.attention()->parameters())) << "the prior moved";
  EXPECT_TRUE(Skills().CheckSameControllers(policy).ok());
  EXPECT_FALSE(AllEqual(head_before, policy.task_head()->parameters())) << "the task head did not learn";
}

// --task_parts R_Arm: the head displaces the right arm's z only; every other part plays the
// prior's z exactly, before and after PPO updates that sample with the returned mask.
TEST(SkillReuseTest, TaskPartsLeaveTheOtherPartsOnThePrior) {
  torch::manual_seed(8);
  TaskNetworks steer = SteerNetworks();
  ModSkillPolicyImpl& policy = *steer.policy;
  auto mask = RestrictTaskHeadToParts(policy, {"R_Arm"}, "5part");
  ASSERT_TRUE(mask.ok()) << mask.status();
  constexpr int64_t kArm = 4, kEmbed = 32;  // R_Arm is the 5part layout's fifth part
  EXPECT_EQ(mask->sum().item<double>(), kEmbed);
  EXPECT_EQ(mask->slice(0, kArm * kEmbed, (kArm + 1) * kEmbed).sum().item<double>(), kEmbed);
  Critic critic(kSteerObs, SmallConfig().critic_hidden);
  torch::optim::Adam optimizer(TrainableParameters(policy, *critic), torch::optim::AdamOptions(1e-3));
  PpoSettings settings;
  settings.minibatch_size = 64;
  settings.sampled_dims = *mask;
  torch::Generator generator = at::detail::createCPUGenerator(8);
  const std::vector<torch::Tensor> head_before = Clones(policy.task_head()->parameters());
  for (int iteration = 0; iteration < 3; ++iteration) {
    PpoBatch batch;
    batch.obs = torch::randn({256, kSteerObs});
    torch::NoGradGuard no_grad;
    const torch::Tensor mean = policy.SampleMean(batch.obs);
    batch.samples = mean + policy.log_std().exp() * torch::randn(mean.sizes()) * *mask;
    batch.old_log_prob = ModSkillPolicyImpl::LogProb(mean, policy.log_std(), batch.samples, *mask);
    batch.old_values = critic->forward(batch.obs);
    batch.advantages = torch::randn({256});
    batch.returns = torch::randn({256});
    torch::AutoGradMode grad(true);
    UpdateWithPpo(policy, *critic, optimizer, batch, settings, generator);
  }
  EXPECT_FALSE(AllEqual(head_before, policy.task_head()->parameters())) << "the arm's head did not learn";
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({8, kSteerObs});
  const torch::Tensor mean = policy.SampleMean(obs);
  EXPECT_EQ(mean.slice(1, 0, kArm * kEmbed).abs().max().item<double>(), 0.0) << "a part outside --task_parts moved";
  EXPECT_GT(mean.slice(1, kArm * kEmbed).abs().max().item<double>(), 0.0);
  SkillAttention attention = policy.attention();
  const torch::Tensor prior = attention->forward(obs).z, z = policy.skills(obs).z;
  EXPECT_TRUE(torch::allclose(z.slice(1, 0, kArm), prior.slice(1, 0, kArm), 1e-6, 1e-6));
  EXPECT_FALSE(torch::allclose(z.select(1, kArm), prior.select(1, kArm), 1e-6, 1e-6));
}

// --task_teacher: with no advantage to follow, the teacher's term alone pulls the arm's z onto the
// teacher's z; the parts outside --task_parts stay on the prior.
TEST(SkillReuseTest, TheTeacherPullsTheHeadsZTowardItsOwn) {
  torch::manual_seed(9);
  TaskNetworks steer = SteerNetworks();
  ModSkillPolicyImpl& policy = *steer.policy;
  auto mask = RestrictTaskHeadToParts(policy, {"R_Arm"}, "5part");
  ASSERT_TRUE(mask.ok()) << mask.status();
  constexpr int64_t kArm = 4, kParts = 5, kEmbed = 32;
  Critic critic(kSteerObs, SmallConfig().critic_hidden);
  torch::optim::Adam optimizer(TrainableParameters(policy, *critic), torch::optim::AdamOptions(1e-3));
  PpoSettings settings;
  settings.minibatch_size = 64;
  settings.sampled_dims = *mask;
  settings.teacher_weight = 1.0;
  settings.teacher_parts = torch::zeros({kParts});
  settings.teacher_parts[kArm] = 1.f;
  torch::Generator generator = at::detail::createCPUGenerator(9);
  const torch::Tensor target = SkillAttentionImpl::NormalizeToSphere(torch::randn({1, kParts, kEmbed}));
  const torch::Tensor probe = torch::randn({32, kSteerObs});
  const auto arm_distance = [&] {
    torch::NoGradGuard no_grad;
    return (policy.skills(probe).z.select(1, kArm) - target.select(1, kArm)).norm(2, -1).mean().item<double>();
  };
  const double before = arm_distance();
  double first_loss = 0, last_loss = 0;
  for (int iteration = 0; iteration < 10; ++iteration) {
    PpoBatch batch;
    batch.obs = torch::randn({256, kSteerObs});
    torch::NoGradGuard no_grad;
    const torch::Tensor mean = policy.SampleMean(batch.obs);
    batch.samples = mean;
    batch.old_log_prob = ModSkillPolicyImpl::LogProb(mean, policy.log_std(), batch.samples, *mask);
    batch.old_values = critic->forward(batch.obs);
    batch.advantages = torch::zeros({256});
    batch.returns = batch.old_values;
    batch.teacher_z = target.expand({256, kParts, kEmbed});
    torch::AutoGradMode grad(true);
    const PpoUpdateStats stats = UpdateWithPpo(policy, *critic, optimizer, batch, settings, generator);
    (iteration == 0 ? first_loss : last_loss) = stats.teacher_loss;
  }
  EXPECT_GT(first_loss, 0.0);
  EXPECT_LT(last_loss, 0.5 * first_loss);
  EXPECT_LT(arm_distance(), 0.5 * before) << "the arm's z did not move toward the teacher's";
  torch::NoGradGuard no_grad;
  SkillAttention attention = policy.attention();
  const torch::Tensor prior = attention->forward(probe).z, z = policy.skills(probe).z;
  EXPECT_TRUE(torch::allclose(z.slice(1, 0, kArm), prior.slice(1, 0, kArm), 1e-6, 1e-6));
}

TEST(SkillReuseTest, TaskPartsNameKnownPartsOverAPrior) {
  TaskNetworks steer = SteerNetworks();
  auto unknown = RestrictTaskHeadToParts(*steer.policy, {"R_Hand"}, "5part");
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(unknown.status().message(), HasSubstr("--task_parts[0]: 'R_Hand' is not a part of the 5part layout"));
  ModelConfig config = Skills().ConfigFor(SmallConfig());
  config.task_skill_prior = false;
  ModSkillPolicy no_prior(LayoutFromWireSpec(Steer()), config);
  auto refused = RestrictTaskHeadToParts(*no_prior, {"R_Arm"}, "5part");
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.status().message(), HasSubstr("--task_parts"));
}

// (ii) The normalizer sees the self features as the tracker's did, and its updates leave them so.
TEST(SkillReuseTest, TrackerStatisticsStayFrozen) {
  torch::manual_seed(4);
  auto tracker = ReadExportedPolicy(Skills().path());
  ASSERT_TRUE(tracker.ok()) << tracker.status();
  const torch::Tensor& tracker_mean = tracker->tensors.at("obs_mean");
  const torch::Tensor& tracker_var = tracker->tensors.at("obs_var");
  // Steer observes what the tracker did: every one of its statistics is the tracker's.
  TaskNetworks steer = SteerNetworks();
  RunningMeanStdImpl& norm = *steer.norm;
  EXPECT_TRUE(torch::equal(norm.mean().slice(0, 0, kSteerGoalStart), tracker_mean));
  EXPECT_TRUE(torch::equal(norm.var().slice(0, 0, kSteerGoalStart), tracker_var));
  EXPECT_EQ(norm.frozen().sum().item<int64_t>(), kSteerGoalStart);
  const torch::Tensor mean_before = norm.mean().clone(), var_before = norm.var().clone();
  for (int i = 0; i < 3; ++i) norm.Update(torch::randn({128, kSteerObs}) * 7.0 + 2.0);
  EXPECT_TRUE(torch::equal(norm.mean().slice(0, 0, kSteerGoalStart), mean_before.slice(0, 0, kSteerGoalStart)));
  EXPECT_TRUE(torch::equal(norm.var().slice(0, 0, kSteerGoalStart), var_before.slice(0, 0, kSteerGoalStart)));
  EXPECT_GT((norm.mean().slice(0, kSteerGoalStart) - mean_before.slice(0, kSteerGoalStart)).abs().min().item<double>(),
            0.5);
  EXPECT_GT(norm.var().slice(0, kSteerGoalStart).min().item<double>(), 10.0) << "the goal dims adapt";

  // VR tracking observes the self features only: those are copied body by body.
  const v1::EnvSpec& vr = SpecsOf("5part", TaskKind::kVrTracking).wire;
  RunningMeanStdImpl vr_norm(vr.obs_size());
  ASSERT_TRUE(Skills().LoadSelfStatistics(Tracking(), vr, vr_norm).ok());
  for (int p = 0; p < vr.parts_size(); ++p) {
    for (int b = 0; b < vr.parts(p).self_obs_size(); ++b) {
      const v1::Slice &from = Tracking().parts(p).self_obs(b), &to = vr.parts(p).self_obs(b);
      EXPECT_TRUE(torch::equal(vr_norm.mean().narrow(0, to.start(), to.size()),
                               tracker_mean.narrow(0, from.start(), from.size())));
      EXPECT_TRUE(torch::equal(vr_norm.var().narrow(0, to.start(), to.size()),
                               tracker_var.narrow(0, from.start(), from.size())));
    }
  }
  EXPECT_EQ(vr_norm.frozen().sum().item<int64_t>(), 358);
}

// (iv) The exported task policy computes the C++ modules' actions from raw observations; the
// server runs it in its task only; the evaluation rebuilds the same policy from the file.
TEST(SkillReuseTest, ExportedTaskPolicyMatchesTheModules) {
  torch::manual_seed(5);
  TaskNetworks steer = SteerNetworks();
  for (int i = 0; i < 2; ++i) steer.norm->Update(torch::randn({64, kSteerObs}) * 2.0 + 1.0);
  PolicySpec spec = PolicySpecForEnv(SpecsOf("5part", TaskKind::kSteer).env);
  spec.controller_input = "proprioception";
  const std::string path = TmpPath("skill_reuse_steer.pt");
  const absl::Status exported = ExportPolicy(steer.policy, steer.norm, spec, path);
  ASSERT_TRUE(exported.ok()) << exported << "\n" << PolicyScriptSource(*steer.policy);

  const torch::Tensor raw = torch::randn({16, kSteerObs}) * 3.0;
  torch::NoGradGuard no_grad;
  const torch::Tensor expected = steer.policy->forward(steer.norm->Normalize(raw));
  torch::jit::Module script = torch::jit::load(path);
  const torch::Tensor scripted = script.forward({raw}).toTensor();
  ASSERT_EQ(scripted.sizes(), expected.sizes());
  EXPECT_LT((scripted - expected).abs().max().item<float>(), 1e-5);

  auto checkpoint = PolicyCheckpoint::LoadFile(path);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_EQ((*checkpoint)->spec().task, "steer");
  EXPECT_TRUE(CheckPolicyFitsEnv((*checkpoint)->spec(), SpecsOf("5part", TaskKind::kSteer).env, "steer").ok());
  const absl::Status in_tracking = CheckPolicyFitsEnv((*checkpoint)->spec(), SpecsOf("5part").env);
  EXPECT_EQ(in_tracking.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(in_tracking.message()), HasSubstr("task steer"));

  auto imported = ImportTaskPolicy(path, Steer());
  ASSERT_TRUE(imported.ok()) << imported.status();
  EXPECT_TRUE(torch::equal(imported->policy->forward(imported->obs_norm->Normalize(raw)), expected));
  EXPECT_THAT(std::string(ImportTaskPolicy(Skills().path(), Steer()).status().message()),
              HasSubstr("a policy for task tracking"));

  PolicySpec wrong_task = spec;
  wrong_task.task = "reach";
  EXPECT_THAT(std::string(ExportPolicy(steer.policy, steer.norm, wrong_task, TmpPath("unused.pt")).message()),
              HasSubstr("task reach"));
}

TEST(SkillReuseTest, NormalizedReturnSumsTheGoalTermsOverTheEpisodeLimit) {
  const TaskReturn steer({"speed", "facing", "energy"}, 0);
  EXPECT_EQ(steer.episode_steps(), 300);
  const torch::Tensor terms = torch::tensor({{0.5f, 0.25f, -0.125f}, {0.0f, 1.0f, -1.0f}});
  const torch::Tensor goal = steer.GoalReward(terms);
  EXPECT_DOUBLE_EQ(goal[0].item<double>(), 0.75);
  EXPECT_DOUBLE_EQ(goal[1].item<double>(), 1.0);
  EXPECT_DOUBLE_EQ(steer.Normalize(150.0), 0.5);
  EXPECT_EQ(TaskReturn({"reach", "energy"}, 100).episode_steps(), 100);
  EXPECT_TRUE(std::isnan(MeanOrNan({})));
  EXPECT_DOUBLE_EQ(MeanOrNan({0.25, 0.75}), 0.5);
}

TEST(SkillReuseTest, EpisodeEndsCountWhyEpisodesEnded) {
  EpisodeEnds ends;
  EXPECT_EQ(ends.Summary(), "-");
  for (int cause : {int{v1::END_CAUSE_FALL}, int{v1::END_CAUSE_TASK}, int{v1::END_CAUSE_FALL}, int{v1::END_CAUSE_TIME}, 250}) {
    ends.Add(cause);
  }
  EXPECT_EQ(ends.total(), 5);
  EXPECT_EQ(ends.count(v1::END_CAUSE_FALL), 2);
  EXPECT_EQ(ends.Summary(), "time 1, fall 2, task 1, unreported 1") << "an unknown cause is unreported";
  EXPECT_EQ(EpisodeEnds::Names(), (std::vector<std::string>{"time", "tracking", "fall", "task", "blow_up"}));
  EXPECT_EQ(ends.Counts(), (std::vector<int>{1, 0, 2, 1, 0}));
  EpisodeEnds more;
  more.Add(v1::END_CAUSE_BLOW_UP);
  ends.Merge(more);
  EXPECT_EQ(ends.count(v1::END_CAUSE_BLOW_UP), 1);

  // On the wire: absent is "not said", a malformed field is the server's fault (DATA_LOSS).
  v1::StepResult result;
  auto absent = ReadEndCauses(result, 3);
  ASSERT_TRUE(absent.ok());
  EXPECT_TRUE(absent->empty());
  const uint8_t causes[3] = {0, 3, 4};
  SetUint8Tensor({3}, causes, result.mutable_end_cause());
  auto read = ReadEndCauses(result, 3);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(*read, (std::vector<int>{0, 3, 4}));
  auto short_field = ReadEndCauses(result, 4);
  EXPECT_EQ(short_field.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(std::string(short_field.status().message()), HasSubstr("StepResult.end_cause"));
}

}  // namespace
}  // namespace modskill::learner
