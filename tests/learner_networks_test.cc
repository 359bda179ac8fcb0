// The learner's networks (learner/): shapes, attention, part independence of the controllers,
// log-probabilities, serialization, the TorchScript export the server runs, the ablations, the
// AMP gradient penalty and the layout checks. Layouts come from the real env spec.
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/script.h>
#include <torch/torch.h>

#include "common/policy/policy_checkpoint.h"
#include "learner/amp_discriminator.h"
#include "learner/amp_loss.h"
#include "learner/critic.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/part_controller.h"
#include "learner/policy_export.h"
#include "learner/running_mean_std.h"
#include "learner/skill_attention.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/policy_fit.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/core/sim/physics_options.h"
#include "server/service/discriminator_scorer.h"
#include "server/service/proto_conversions.h"
#include "tests/env_specs.h"
#include "tests/test_files.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;


const EnvSpec& Spec(const std::string& layout_name) { return SpecsOf(layout_name).env; }

NetworkLayout Layout(const std::string& name = "5part") { return LayoutFromWireSpec(SpecsOf(name).wire); }

ModelConfig Config(const std::string& preset = "small") {
  auto config = ModelConfig::Preset(preset);
  EXPECT_TRUE(config.ok()) << config.status();
  return *config;
}

std::string TmpPath(const std::string& name) {
  return ProcessTempDir("networks") + "/" + name;
}

// The spec of the server's env, as a checkpoint stores it.
PolicySpec SpecOf(const std::string& layout_name = "5part") { return PolicySpecForEnv(Spec(layout_name)); }

// Observation statistics as after some training: per-feature means and variances far from 0 and 1.
RunningMeanStd TrainedNormalizer(int64_t size) {
  RunningMeanStd norm(size);
  for (int i = 0; i < 3; ++i) norm->Update(torch::randn({64, size}) * 3.0 + torch::linspace(-2, 2, size));
  return norm;
}

TEST(LearnerNetworksTest, EnvLayoutMatchesTheEnvSpec) {
  const NetworkLayout layout = Layout("5part");
  EXPECT_EQ(layout.obs_size, 934);
  EXPECT_EQ(layout.action_size, 69);
  EXPECT_EQ(layout.amp_obs_size, 2320);
  ASSERT_EQ(layout.parts.size(), 5u);
  const std::vector<int64_t> action_sizes = {12, 12, 15, 15, 15};
  for (size_t p = 0; p < 5; ++p) EXPECT_EQ(layout.parts[p].action_size, action_sizes[p]) << layout.parts[p].name;
  EXPECT_TRUE(layout.Validate().ok()) << layout.Validate();
}

// (1) z is [B, P, E] with unit norm, for every layout of the catalog and both presets.
TEST(LearnerNetworksTest, EmbeddingShapesAndUnitNorms) {
  torch::manual_seed(1);
  struct Case {
    std::string layout, preset;
    int64_t parts;
  };
  for (const Case& c : std::vector<Case>{{"1part", "small", 1},
                                         {"2part", "small", 2},
                                         {"3part", "small", 3},
                                         {"5part", "small", 5},
                                         {"5part", "paper", 5}}) {
    SCOPED_TRACE(c.layout + " " + c.preset);
    const NetworkLayout layout = Layout(c.layout);
    const ModelConfig config = Config(c.preset);
    ModSkillPolicy policy(layout, config);
    const int64_t batch = 4;
    const torch::Tensor obs = torch::randn({batch, layout.obs_size});
    torch::NoGradGuard no_grad;
    const SkillAttentionOutput skills = policy->skills(obs);
    EXPECT_EQ(skills.z.sizes(), (std::vector<int64_t>{batch, c.parts, config.embed_dim}));
    EXPECT_EQ(skills.attention.sizes(), (std::vector<int64_t>{batch, c.parts, c.parts}));
    EXPECT_TRUE(torch::allclose(skills.z.norm(2, -1), torch::ones({batch, c.parts}), 1e-5, 1e-5));
    EXPECT_EQ(policy->forward(obs).sizes(), (std::vector<int64_t>{batch, layout.action_size}));
    Critic critic(layout.obs_size, config.critic_hidden);
    EXPECT_EQ(critic->forward(obs).sizes(), (std::vector<int64_t>{batch}));
  }
  EXPECT_EQ(Config("paper").embed_dim, 64);
  EXPECT_EQ(Config("paper").controller_hidden, (std::vector<int64_t>{2048, 1536, 1024, 512}));
  EXPECT_EQ(Config("small").embed_dim, 32);
}

// (2) Attention rows are distributions; with attention on they mix parts, with it off they are the identity.
TEST(LearnerNetworksTest, AttentionRowsSumToOne) {
  torch::manual_seed(2);
  const NetworkLayout layout = Layout("5part");
  const torch::Tensor obs = torch::randn({8, layout.obs_size});
  const torch::Tensor eye = torch::eye(5).expand({8, 5, 5});
  torch::NoGradGuard no_grad;

  SkillAttention attention(layout, Config());
  const SkillAttentionOutput on = attention->forward(obs);
  EXPECT_TRUE(torch::allclose(on.attention.sum(-1), torch::ones({8, 5}), 1e-5, 1e-6));
  EXPECT_TRUE((on.attention >= 0).all().item<bool>());
  EXPECT_GT((on.attention - eye).abs().max().item<float>(), 1e-3);

  ModelConfig off_config = Config();
  off_config.attention = false;
  SkillAttention no_attention(layout, off_config);
  EXPECT_TRUE(no_attention->keys().empty());
  const SkillAttentionOutput off = no_attention->forward(obs);
  EXPECT_TRUE(torch::equal(off.attention, eye));
  // z_k is part k's own value, normalized.
  const PartSlices& torso = layout.parts[2];
  Mlp torso_value = no_attention->values()[2];
  const torch::Tensor v = torso_value->forward(obs.slice(1, torso.obs_start, torso.obs_start + torso.obs_size));
  EXPECT_TRUE(torch::allclose(off.z.select(1, 2), v / v.norm(2, -1, true), 1e-5, 1e-6));
}

// (3) Part k's controller moves only part k's actions.
TEST(LearnerNetworksTest, PartControllerOnlyMovesItsOwnPart) {
  torch::manual_seed(3);
  const NetworkLayout layout = Layout("5part");
  ModSkillPolicy policy(layout, Config());
  const torch::Tensor means = policy->forward(torch::randn({4, layout.obs_size}));
  const size_t num_parts = layout.parts.size();
  ASSERT_EQ(policy->controllers().size(), num_parts);
  for (size_t k = 0; k < num_parts; ++k) {
    const PartSlices& part = layout.parts[k];
    SCOPED_TRACE(part.name);
    const torch::Tensor part_means = means.slice(1, part.action_start, part.action_start + part.action_size);
    for (size_t j = 0; j < num_parts; ++j) {
      const std::vector<torch::Tensor> params = policy->controllers()[j]->parameters();
      const auto grads = torch::autograd::grad({part_means.sum()}, params, {}, /*retain_graph=*/true,
                                               /*create_graph=*/false, /*allow_unused=*/true);
      double norm = 0;
      for (const torch::Tensor& g : grads) {
        if (g.defined()) norm += g.abs().sum().item<double>();
      }
      if (j != k) {
        EXPECT_EQ(norm, 0.0) << "controller of " << layout.parts[j].name;
      }
    }
    // Every action of part k depends on part k's controller.
    const std::vector<torch::Tensor> own = policy->controllers()[k]->parameters();
    for (int64_t a = 0; a < part.action_size; ++a) {
      const auto grads = torch::autograd::grad({part_means.select(1, a).sum()}, own, {}, /*retain_graph=*/true);
      double norm = 0;
      for (const torch::Tensor& g : grads) norm += g.abs().sum().item<double>();
      EXPECT_GT(norm, 0.0) << "action " << part.action_start + a;
    }
  }
}

// (4) log N(mean | mean, sigma) = -A/2 log(2 pi) - sum(log sigma).
TEST(LearnerNetworksTest, LogProbOfTheMean) {
  torch::manual_seed(4);
  const NetworkLayout layout = Layout("5part");
  ModSkillPolicy policy(layout, Config());
  EXPECT_TRUE(torch::allclose(policy->log_std(), torch::full({layout.action_size}, -2.9)));
  torch::NoGradGuard no_grad;
  const torch::Tensor mean = policy->forward(torch::randn({3, layout.obs_size}));
  const torch::Tensor log_prob = ModSkillPolicyImpl::LogProb(mean, policy->log_std(), mean);
  const double a = static_cast<double>(layout.action_size);
  const double expected = -0.5 * a * std::log(2 * M_PI) + 2.9 * a;
  ASSERT_EQ(log_prob.sizes(), (std::vector<int64_t>{3}));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(log_prob[i].item<double>(), expected, 1e-3);
  // One sigma away in one coordinate costs 1/2.
  torch::Tensor moved = mean.clone();
  moved.select(1, 0) += std::exp(-2.9);
  EXPECT_NEAR(ModSkillPolicyImpl::LogProb(mean, policy->log_std(), moved)[0].item<double>(), expected - 0.5, 1e-3);
  // Dims marked 0 in sampled_dims act on their mean: they carry no probability, however far off.
  torch::Tensor sampled = torch::ones({layout.action_size});
  sampled[0] = 0.f;
  const double one_less = -0.5 * (a - 1) * std::log(2 * M_PI) + 2.9 * (a - 1);
  EXPECT_NEAR(ModSkillPolicyImpl::LogProb(mean, policy->log_std(), moved, sampled)[0].item<double>(), one_less, 1e-3);
  moved.select(1, 1) += std::exp(-2.9);
  EXPECT_NEAR(ModSkillPolicyImpl::LogProb(mean, policy->log_std(), moved, sampled)[0].item<double>(), one_less - 0.5,
              1e-3);
}

// (5) torch::save -> torch::load into a fresh module reproduces the outputs.
TEST(LearnerNetworksTest, SaveLoadRoundTrip) {
  torch::manual_seed(5);
  const NetworkLayout layout = Layout("5part");
  const ModelConfig config = Config();
  ModSkillPolicy policy(layout, config);
  RunningMeanStd norm = TrainedNormalizer(layout.obs_size);
  Critic critic(layout.obs_size, config.critic_hidden);
  AmpDiscriminator disc(layout.amp_obs_size, config.discriminator_hidden);
  const std::string policy_path = TmpPath("learner_policy.pt"), norm_path = TmpPath("learner_norm.pt"),
                    critic_path = TmpPath("learner_critic.pt"), disc_path = TmpPath("learner_disc.pt");
  torch::save(policy, policy_path);
  torch::save(norm, norm_path);
  torch::save(critic, critic_path);
  torch::save(disc, disc_path);

  torch::manual_seed(55);
  ModSkillPolicy loaded(layout, config);
  RunningMeanStd loaded_norm(layout.obs_size);
  Critic loaded_critic(layout.obs_size, config.critic_hidden);
  AmpDiscriminator loaded_disc(layout.amp_obs_size, config.discriminator_hidden);
  torch::load(loaded, policy_path);
  torch::load(loaded_norm, norm_path);
  torch::load(loaded_critic, critic_path);
  torch::load(loaded_disc, disc_path);

  torch::NoGradGuard no_grad;
  const torch::Tensor raw = torch::randn({6, layout.obs_size}) * 4;
  const torch::Tensor obs = norm->Normalize(raw);
  EXPECT_TRUE(torch::equal(loaded_norm->Normalize(raw), obs));
  EXPECT_TRUE(torch::equal(loaded_norm->count(), norm->count()));
  EXPECT_TRUE(torch::equal(loaded->forward(obs), policy->forward(obs)));
  EXPECT_TRUE(torch::equal(loaded->skills(obs).attention, policy->skills(obs).attention));
  EXPECT_TRUE(torch::equal(loaded_critic->forward(obs), critic->forward(obs)));
  const torch::Tensor amp = torch::randn({6, layout.amp_obs_size});
  EXPECT_TRUE(torch::equal(loaded_disc->forward(amp), disc->forward(amp)));
}

// Return normalization: the MLP predicts (return - mean) / std of the running return
// statistics, forward() gives values in reward units, and the mode and statistics survive a save.
TEST(LearnerNetworksTest, CriticNormalizesReturnsAndRoundTrips) {
  torch::manual_seed(21);
  Critic critic(12, std::vector<int64_t>{16}, /*normalize_returns=*/true);
  ASSERT_TRUE(critic->normalizes_returns());
  const torch::Tensor returns = torch::randn({500}) * 10 + 50;
  critic->return_statistics().Update(returns.unsqueeze(1));
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({8, 12});
  const double mean = returns.mean().item<double>(), std = returns.std(/*unbiased=*/false).item<double>();
  EXPECT_TRUE(torch::allclose(critic->forward(obs), critic->NormalizedValue(obs) * std + mean, 1e-4, 1e-3));
  EXPECT_TRUE(torch::allclose(critic->NormalizeReturns(returns).mean(), torch::zeros({}), 1e-4, 1e-4));
  EXPECT_NEAR(critic->NormalizeReturns(returns).std(/*unbiased=*/false).item<double>(), 1.0, 1e-4);

  const std::string path = (std::filesystem::temp_directory_path() / "critic_normalized.pt").string();
  torch::save(critic, path);
  Critic loaded(12, std::vector<int64_t>{16});  // built without normalization: the saved mode wins
  torch::load(loaded, path);
  EXPECT_TRUE(loaded->normalizes_returns());
  EXPECT_TRUE(torch::equal(loaded->forward(obs), critic->forward(obs)));
  std::filesystem::remove(path);
}

// A critic saved before return normalization (its archive holds the MLP alone) loads as one that
// predicts raw returns, with the same outputs.
TEST(LearnerNetworksTest, CriticFromBeforeReturnNormalizationLoadsRaw) {
  torch::manual_seed(22);
  Critic old(12, std::vector<int64_t>{16});
  torch::serialize::OutputArchive archive, mlp;
  old->named_children()["mlp"]->save(mlp);
  archive.write("mlp", mlp);
  std::ostringstream bytes(std::ios::binary);
  archive.save_to(bytes);

  Critic loaded(12, std::vector<int64_t>{16}, /*normalize_returns=*/true);
  torch::serialize::InputArchive in;
  std::istringstream stream(bytes.str(), std::ios::binary);
  in.load_from(stream);
  loaded->load(in);
  EXPECT_FALSE(loaded->normalizes_returns());
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({5, 12});
  EXPECT_TRUE(torch::equal(loaded->forward(obs), old->forward(obs)));
  const torch::Tensor returns = torch::randn({5}) * 30;
  EXPECT_TRUE(torch::equal(loaded->NormalizeReturns(returns), returns));
}

// RunningMeanStd: merging batches gives the statistics of their union.
TEST(LearnerNetworksTest, RunningMeanStdMergesBatches) {
  torch::manual_seed(6);
  const torch::Tensor data = torch::randn({300, 7}, torch::kFloat64) * 2.5 + 10.0;
  RunningMeanStd norm(7);
  norm->Update(data.slice(0, 0, 1));
  norm->Update(data.slice(0, 1, 120));
  norm->Update(data.slice(0, 120, 300));
  EXPECT_EQ(norm->count().item<double>(), 300.0);
  EXPECT_TRUE(torch::allclose(norm->mean(), data.mean(0), 1e-12, 1e-10));
  EXPECT_TRUE(torch::allclose(norm->var(), data.var(0, /*unbiased=*/false), 1e-12, 1e-10));
  const torch::Tensor x = torch::tensor({{1000.0f, -1000.0f, 10.0f, 10.0f, 10.0f, 10.0f, 10.0f}});
  const torch::Tensor normalized = norm->Normalize(x);
  EXPECT_EQ(normalized.scalar_type(), torch::kFloat32);
  EXPECT_FLOAT_EQ(normalized[0][0].item<float>(), 5.0f);
  EXPECT_FLOAT_EQ(normalized[0][1].item<float>(), -5.0f);
}

// Exports, checks the TorchScript against the C++ modules and the server's loader against both.
void ExpectExportMatches(ModSkillPolicy& policy, const std::string& layout_name, const std::string& file) {
  const NetworkLayout& layout = policy->layout();
  RunningMeanStd norm = TrainedNormalizer(layout.obs_size);
  const PolicySpec spec = SpecOf(layout_name);
  const std::string path = TmpPath(file);
  const absl::Status exported = ExportPolicy(policy, norm, spec, path);
  ASSERT_TRUE(exported.ok()) << exported << "\n" << PolicyScriptSource(*policy);

  const int n = 16;
  const torch::Tensor raw = torch::randn({n, layout.obs_size}) * 3.0;
  torch::Tensor expected;
  {
    torch::NoGradGuard no_grad;
    expected = policy->forward(norm->Normalize(raw));
  }
  torch::jit::Module script = torch::jit::load(path);
  const torch::Tensor scripted = script.forward({raw}).toTensor();
  ASSERT_EQ(scripted.sizes(), expected.sizes());
  EXPECT_LT((scripted - expected).abs().max().item<float>(), 1e-5);

  auto checkpoint = PolicyCheckpoint::LoadFile(path);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_EQ((*checkpoint)->spec().ToJson(), spec.ToJson());
  EXPECT_TRUE(CheckPolicyFitsEnv((*checkpoint)->spec(), Spec(layout_name)).ok());
  const torch::Tensor input = raw.contiguous();
  std::vector<float> actions(static_cast<size_t>(n) * layout.action_size);
  const absl::Status acted = (*checkpoint)->Act(input.data_ptr<float>(), n, actions.data());
  ASSERT_TRUE(acted.ok()) << acted;
  const torch::Tensor served = torch::from_blob(actions.data(), {n, layout.action_size}).clone();
  EXPECT_LT((served - expected).abs().max().item<float>(), 1e-5);
}

// (6) The exported TorchScript computes the C++ policy's actions from raw observations.
TEST(LearnerNetworksTest, ExportedTorchScriptMatchesTheModules) {
  torch::manual_seed(7);
  for (const std::string layout_name : {"5part", "3part", "1part"}) {
    SCOPED_TRACE(layout_name);
    ModSkillPolicy policy(Layout(layout_name), Config());
    ExpectExportMatches(policy, layout_name, "learner_export_" + layout_name + ".pt");
  }
}

TEST(LearnerNetworksTest, ExportRejectsAMismatchedSpec) {
  ModSkillPolicy policy(Layout("5part"), Config());
  RunningMeanStd norm(934);
  const absl::Status status = ExportPolicy(policy, norm, SpecOf("5part"), TmpPath("unused.pt"));
  EXPECT_TRUE(status.ok()) << status;
  PolicySpec wrong = SpecOf("5part");
  wrong.action_size = 68;
  EXPECT_THAT(ExportPolicy(policy, norm, wrong, TmpPath("unused.pt")).message(), HasSubstr("action_size"));
  RunningMeanStd small_norm(10);
  EXPECT_THAT(ExportPolicy(policy, small_norm, SpecOf("5part"), TmpPath("unused.pt")).message(),
              HasSubstr("obs_norm"));
}

// The discriminator as the server's plausibility scorer: the AMP reward of normalized input, as
// the trainer computes it; the server side loads it and scores clips with it.
TEST(LearnerNetworksTest, ExportedDiscriminatorScorerIsTheAmpReward) {
  torch::manual_seed(9);
  const int64_t width = 2320;
  AmpDiscriminator discriminator(width, std::vector<int64_t>{64, 32});
  RunningMeanStd norm(width);
  norm->Update(torch::randn({64, width}) * 2 + 0.5);
  auto bytes = ExportDiscriminatorScorer(*discriminator, *norm);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  std::istringstream in(*bytes, std::ios::binary);
  torch::jit::Module module = torch::jit::load(in);
  const torch::Tensor x = torch::randn({16, width}) * 3;
  const torch::Tensor expected = AmpReward(discriminator->forward(norm->Normalize(x))).reshape({-1});
  const torch::Tensor scored = module.forward({x}).toTensor();
  ASSERT_EQ(scored.sizes(), expected.sizes());
  EXPECT_LT((scored - expected).abs().max().item<float>(), 1e-5);
  EXPECT_GE(scored.min().item<float>(), 0.f);
  EXPECT_LE(scored.max().item<float>(), 1.f);
  // The server sends its whole AMP history; a discriminator of fewer frames reads the newest.
  const torch::Tensor older_frames = torch::randn({16, 2 * width}) * 5;
  const torch::Tensor history = torch::cat({x, older_frames}, 1);
  EXPECT_TRUE(torch::allclose(module.forward({history}).toTensor(), scored));

  auto scorer = DiscriminatorScorer::LoadBytes(*bytes, width);
  ASSERT_TRUE(scorer.ok()) << scorer.status();
  // A server with a shorter AMP history than the discriminator reads cannot use it.
  EXPECT_EQ(DiscriminatorScorer::LoadBytes(*bytes, width - 1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(DiscriminatorScorer::LoadBytes("not torchscript", width).status().message()),
              HasSubstr("discriminator"));
  RunningMeanStd wrong(10);
  EXPECT_FALSE(ExportDiscriminatorScorer(*discriminator, *wrong).ok());
}

// (7) The ablations: one whole-body controller; no attention.
TEST(LearnerNetworksTest, AblationsBuildRunAndExport) {
  torch::manual_seed(8);
  const NetworkLayout layout = Layout("5part");
  ModelConfig whole_body = Config();
  whole_body.whole_body = true;
  ModSkillPolicy whole(layout, whole_body);
  ASSERT_EQ(whole->controllers().size(), 1u);
  EXPECT_EQ(whole->controllers()[0]->input_size(), 5 * whole_body.embed_dim + layout.obs_size);
  EXPECT_EQ(whole->controllers()[0]->action_size(), layout.action_size);
  ExpectExportMatches(whole, "5part", "learner_export_whole_body.pt");

  ModelConfig no_attention = Config();
  no_attention.attention = false;
  ModSkillPolicy plain(layout, no_attention);
  ExpectExportMatches(plain, "5part", "learner_export_no_attention.pt");

  ModelConfig both = whole_body;
  both.attention = false;
  ModSkillPolicy neither(layout, both);
  ExpectExportMatches(neither, "5part", "learner_export_whole_body_no_attention.pt");
}

// Proprioceptive controllers (skill reuse): each reads z_p and exactly its bodies' self
// features, so changing only the reference features changes the actions through z alone; the
// export computes the same.
TEST(LearnerNetworksTest, ProprioceptiveControllersReadTheReferenceOnlyThroughZ) {
  torch::manual_seed(9);
  const NetworkLayout layout = Layout("5part");
  const EnvSpec& env = Spec("5part");
  ModelConfig config = Config();
  config.controller_input = ModelConfig::ControllerInput::kProprioception;
  ModSkillPolicy policy(layout, config);
  // The server describes each body's self block: 13 for the root, 15 for every other body.
  int64_t self_total = 0;
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    const PartSlices& part = layout.parts[p];
    ASSERT_EQ(part.self_obs.size(), env.layout.parts[p].bodies.size()) << part.name;
    EXPECT_EQ(policy->controllers()[p]->input_size(), config.embed_dim + part.self_obs_size()) << part.name;
    self_total += part.self_obs_size();
  }
  EXPECT_EQ(self_total, env.self_obs_size);

  // A mask of the self features: perturbing everything else leaves every ControllerState alone.
  torch::Tensor is_self = torch::zeros({layout.obs_size}, torch::kBool);
  for (const PartSlices& part : layout.parts) {
    for (const auto& [start, size] : part.self_obs) is_self.slice(0, start, start + size).fill_(true);
  }
  const torch::Tensor obs = torch::randn({8, layout.obs_size});
  const torch::Tensor reference_changed = torch::where(is_self, obs, obs + torch::randn({8, layout.obs_size}));
  torch::NoGradGuard no_grad;
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    EXPECT_TRUE(torch::equal(policy->ControllerState(obs, p), policy->ControllerState(reference_changed, p)));
  }
  // ... while the actions do change (through z), and changing a self feature changes its part's state.
  EXPECT_GT((policy->forward(obs) - policy->forward(reference_changed)).abs().max().item<float>(), 1e-4);
  torch::Tensor self_changed = obs.clone();
  const auto [knee_start, knee_size] = layout.parts[0].self_obs[1];
  self_changed.slice(1, knee_start, knee_start + knee_size) += 1.0;
  EXPECT_FALSE(torch::equal(policy->ControllerState(obs, 0), policy->ControllerState(self_changed, 0)));
  ExpectExportMatches(policy, "5part", "learner_export_proprioceptive.pt");

  EXPECT_FALSE(ParseControllerInput("reference").ok());
  EXPECT_THAT(std::string(ParseControllerInput("reference").status().message()), HasSubstr("--controller_input"));
  // A self slice outside its part's obs slice is a layout error naming the part.
  NetworkLayout outside = layout;
  outside.parts[1].self_obs[0].first = 0;
  EXPECT_THAT(std::string(outside.Validate().message()), HasSubstr(outside.parts[1].name));
}

// (8) The AMP gradient penalty: positive in general, zero when the logit ignores its input.
TEST(LearnerNetworksTest, GradientPenalty) {
  torch::manual_seed(9);
  const NetworkLayout layout = Layout("5part");
  const ModelConfig config = Config();
  AmpDiscriminator disc(layout.amp_obs_size, config.discriminator_hidden);
  const torch::Tensor expert = torch::randn({8, layout.amp_obs_size});
  EXPECT_EQ(disc->forward(expert).sizes(), (std::vector<int64_t>{8}));
  const torch::Tensor penalty = disc->GradientPenalty(expert);
  EXPECT_EQ(penalty.dim(), 0);
  EXPECT_GT(penalty.item<float>(), 0.0f);
  // It trains: its gradient reaches the first layer.
  penalty.backward();
  EXPECT_GT(disc->mlp()->layers()[0]->weight.grad().abs().sum().item<float>(), 0.0f);

  {
    torch::NoGradGuard no_grad;
    disc->mlp()->output_layer()->weight.zero_();
  }
  EXPECT_EQ(disc->GradientPenalty(expert).item<float>(), 0.0f);
}

// (9) Bad layouts and unknown presets name the problem.
TEST(LearnerNetworksTest, BadLayoutAndUnknownPreset) {
  NetworkLayout overlapping = Layout("5part");
  overlapping.parts[2].obs_start -= 3;
  absl::Status status = overlapping.Validate();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("'Torso'"));
  EXPECT_THAT(status.message(), HasSubstr("overlaps"));
  EXPECT_THROW(ModSkillPolicy(overlapping, Config()), c10::Error);

  NetworkLayout gap = Layout("5part");
  gap.parts[4].action_start += 1;
  EXPECT_THAT(gap.Validate().message(), HasSubstr("'R_Arm'"));
  EXPECT_THAT(gap.Validate().message(), HasSubstr("action"));

  NetworkLayout short_layout = Layout("5part");
  short_layout.obs_size += 1;
  EXPECT_THAT(short_layout.Validate().message(), HasSubstr("obs_size"));

  NetworkLayout empty_part = Layout("5part");
  empty_part.parts[0].action_size = 0;
  EXPECT_THAT(empty_part.Validate().message(), HasSubstr("'L_Leg'"));

  auto preset = ModelConfig::Preset("huge");
  EXPECT_EQ(preset.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(preset.status().message(), HasSubstr("'huge'"));
}

}  // namespace
}  // namespace modskill::learner
