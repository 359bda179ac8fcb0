// Skill composition and interpolation (issue 13): the exported policy's skills() and
// act_with_z(), an older export re-exported with them (and with its physics recorded), and the server's Rollout recording z
// (record_skills) and composing it across clips (composition), with the bad inputs it refuses.
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <torch/script.h>
#include <torch/torch.h>

#include "common/atomic_file.h"
#include "common/policy/physics_settings.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/tensor_codec.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/policy_export.h"
#include "learner/policy_import.h"
#include "learner/policy_upgrade.h"
#include "learner/running_mean_std.h"
#include "server/core/env/skill_composition.h"
#include "tests/env_specs.h"
#include "tests/simulation_server_fixture.h"

namespace modskill {
namespace {

using learner::ExportPolicy;
using learner::LayoutFromWireSpec;
using learner::ModelConfig;
using learner::ModSkillPolicy;
using learner::RunningMeanStd;
using ::testing::HasSubstr;

constexpr int kParts = 5;
constexpr int kSteps = 30;  // per clip, to keep the rollouts short

// A small 5-part tracker with random weights and trained-looking statistics, exported.
std::string ExportTracker(const std::string& name, bool whole_body = false, bool proprioceptive = false) {
  torch::manual_seed(3);
  ModelConfig config = *ModelConfig::Preset("small");
  config.whole_body = whole_body;
  if (proprioceptive) config.controller_input = ModelConfig::ControllerInput::kProprioception;
  ModSkillPolicy policy(LayoutFromWireSpec(SpecsOf("5part").wire), config);
  RunningMeanStd norm(SpecsOf("5part").wire.obs_size());
  for (int i = 0; i < 3; ++i) norm->Update(torch::randn({64, norm->size()}) * 2.0);
  PolicySpec spec = PolicySpecForEnv(SpecsOf("5part").env);
  spec.action = ActionMapping{ActionMode::kResidual, 0.5};
  if (proprioceptive) spec.controller_input = kProprioceptionControllerInput;
  const std::string path = TempDir() + "/" + name;
  const absl::Status exported = ExportPolicy(policy, norm, spec, path);
  EXPECT_TRUE(exported.ok()) << exported;
  return path;
}

// A steer policy (task head over proprioceptive controllers), exported.
std::string ExportSteerPolicy() {
  ModelConfig config = *ModelConfig::Preset("small");
  config.controller_input = ModelConfig::ControllerInput::kProprioception;
  ModSkillPolicy policy(LayoutFromWireSpec(SpecsOf("5part", TaskKind::kSteer).wire), config);
  RunningMeanStd norm(SpecsOf("5part", TaskKind::kSteer).wire.obs_size());
  PolicySpec spec = PolicySpecForEnv(SpecsOf("5part", TaskKind::kSteer).env);
  spec.task = "steer";
  spec.controller_input = kProprioceptionControllerInput;
  const std::string path = TempDir() + "/steer_policy.pt";
  const absl::Status exported = ExportPolicy(policy, norm, spec, path);
  EXPECT_TRUE(exported.ok()) << exported;
  return path;
}

const std::string& Tracker() {
  static const std::string* path = new std::string(ExportTracker("composition_tracker.pt"));
  return *path;
}

// The same archive as exported before skill composition: its tensors and forward only.
std::string OldExport(const std::string& path, const std::string& name) {
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}};
  torch::jit::Module current = torch::jit::load(path, torch::kCPU, extra);
  torch::jit::Module old("ModSkillPolicy");
  for (const auto& p : current.named_parameters(false)) old.register_parameter(p.name, p.value, false);
  for (const auto& b : current.named_buffers(false)) old.register_buffer(b.name, b.value);
  ModSkillPolicy policy(LayoutFromWireSpec(SpecsOf("5part").wire), *ModelConfig::Preset("small"));
  const std::string source = learner::PolicyScriptSource(*policy);
  old.define(source.substr(0, source.find("def skills")));
  const std::string out = TempDir() + "/" + name;
  std::ostringstream bytes(std::ios::binary);
  old.save(bytes, extra);
  EXPECT_TRUE(WriteFileAtomically(out, bytes.str()).ok());
  return out;
}

std::vector<float> RandomObs(int n) {
  torch::manual_seed(5);
  const torch::Tensor obs = torch::randn({n, SpecsOf("5part").wire.obs_size()}) * 2.0;
  return std::vector<float>(obs.data_ptr<float>(), obs.data_ptr<float>() + obs.numel());
}

TEST(SkillExportTest, ForwardIsActWithZOfSkillsAndZIsOnTheSphere) {
  for (bool proprioceptive : {false, true}) {
    const std::string path = ExportTracker(proprioceptive ? "proprio_tracker.pt" : "obs_tracker.pt", false, proprioceptive);
    torch::jit::Module module = torch::jit::load(path);
    torch::NoGradGuard no_grad;
    torch::manual_seed(11);
    const torch::Tensor obs = torch::randn({8, SpecsOf("5part").wire.obs_size()}) * 2.0;
    const torch::Tensor z = module.get_method("skills")({obs}).toTensor();
    ASSERT_EQ(z.sizes(), (std::vector<int64_t>{8, kParts, 32}));
    EXPECT_LT((z.norm(2, -1) - 1).abs().max().item<double>(), 1e-5);
    const torch::Tensor actions = module.forward({obs}).toTensor();
    EXPECT_TRUE(torch::equal(actions, module.get_method("act_with_z")({obs, z}).toTensor()));
  }
}

// Part p's controller reads z_p only: changing z_p moves part p's actions and no other part's.
TEST(SkillExportTest, SwappingOnePartsZMovesOnlyThatPartsActions) {
  auto checkpoint = PolicyCheckpoint::LoadFile(Tracker());
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  ASSERT_TRUE((*checkpoint)->has_skills());
  ASSERT_TRUE((*checkpoint)->has_part_controllers());
  ASSERT_EQ((*checkpoint)->skill_parts(), kParts);
  const int n = 2, embed = (*checkpoint)->embed_dim(), actions_size = (*checkpoint)->spec().action_size;
  const std::vector<float> obs = RandomObs(n);
  std::vector<float> z(n * kParts * embed), base(n * actions_size), swapped(n * actions_size);
  ASSERT_TRUE((*checkpoint)->Skills(obs.data(), n, z.data()).ok());
  ASSERT_TRUE((*checkpoint)->ActWithZ(obs.data(), z.data(), n, base.data()).ok());
  // Env 0 takes env 1's z for part 3 (L_Arm: actions [39, 54)).
  const int part = 3, first = 39, last = 54;
  std::copy_n(z.begin() + (kParts + part) * embed, embed, z.begin() + part * embed);
  ASSERT_TRUE((*checkpoint)->ActWithZ(obs.data(), z.data(), n, swapped.data()).ok());
  double moved_inside = 0;
  for (int a = 0; a < actions_size; ++a) {
    if (a >= first && a < last) {
      moved_inside += std::abs(swapped[a] - base[a]);
    } else {
      EXPECT_EQ(swapped[a], base[a]) << "action " << a;
    }
  }
  EXPECT_GT(moved_inside, 1e-4);
  for (int a = actions_size; a < n * actions_size; ++a) EXPECT_EQ(swapped[a], base[a]);
}

TEST(SkillExportTest, AnOldExportHasNoSkillsAndIsReexportedWithThem) {
  const std::string old = OldExport(Tracker(), "old_tracker.pt");
  auto checkpoint = PolicyCheckpoint::LoadFile(old);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_FALSE((*checkpoint)->has_skills());
  std::vector<float> z(1000);
  EXPECT_EQ((*checkpoint)->Skills(RandomObs(1).data(), 1, z.data()).code(), absl::StatusCode::kFailedPrecondition);

  auto exported = learner::ReadExportedPolicy(old);
  ASSERT_TRUE(exported.ok()) << exported.status();
  const std::string upgraded = TempDir() + "/upgraded_tracker.pt";
  auto upgrade = learner::UpgradePolicy(*exported, SpecsOf("5part").wire, upgraded);
  ASSERT_TRUE(upgrade.ok()) << upgrade.status();
  EXPECT_EQ(upgrade->parts, kParts);
  EXPECT_LT(upgrade->forward_difference, 1e-6);
  EXPECT_FALSE(upgrade->physics_added);  // it had its record already
  torch::NoGradGuard no_grad;
  const torch::Tensor obs = torch::randn({4, SpecsOf("5part").wire.obs_size()}) * 2.0;
  torch::jit::Module before = torch::jit::load(old), after = torch::jit::load(upgraded);
  EXPECT_TRUE(torch::equal(before.forward({obs}).toTensor(), after.forward({obs}).toTensor()));
  auto reloaded = PolicyCheckpoint::LoadFile(upgraded);
  ASSERT_TRUE(reloaded.ok());
  EXPECT_TRUE((*reloaded)->has_skills());
}

// A file from before policies recorded their physics gains the server's; a file that records
// other physics than the server's is refused by name, and nothing is written.
TEST(SkillExportTest, AnUpgradeRecordsTheServersPhysicsAndRefusesOtherPhysics) {
  auto exported = learner::ReadExportedPolicy(OldExport(Tracker(), "old_for_physics.pt"));
  ASSERT_TRUE(exported.ok()) << exported.status();
  ASSERT_TRUE(exported->spec.physics.recorded());
  const PhysicsSettings trained = exported->spec.physics;

  learner::ExportedPolicy unrecorded = *exported;
  unrecorded.spec.physics = PhysicsSettings{};
  const std::string stamped = TempDir() + "/upgraded_with_physics.pt";
  auto upgrade = learner::UpgradePolicy(unrecorded, SpecsOf("5part").wire, stamped);
  ASSERT_TRUE(upgrade.ok()) << upgrade.status();
  EXPECT_TRUE(upgrade->physics_added);
  auto reread = learner::ReadExportedPolicy(stamped);
  ASSERT_TRUE(reread.ok()) << reread.status();
  EXPECT_EQ(reread->spec.physics.ToJson(), trained.ToJson());

  v1::EnvSpec stiffer = SpecsOf("5part").wire;
  stiffer.mutable_physics()->set_pd_gain_scale(2);
  const std::string refused = TempDir() + "/upgraded_refused.pt";
  std::filesystem::remove(refused);
  auto mismatch = learner::UpgradePolicy(*exported, stiffer, refused);
  EXPECT_EQ(mismatch.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(mismatch.status().message()), HasSubstr("pd_gain_scale 1 against this server's 2"));
  EXPECT_FALSE(std::filesystem::exists(refused));
  EXPECT_FALSE(std::filesystem::exists(refused + ".upgrade"));
}

// A task policy is saved again as it is (same forward, same task, skills() kept), now with the
// server's physics, and other physics than the server's is refused as for a tracker.
TEST(SkillExportTest, AnUpgradeStampsATaskPolicyWithoutRebuildingIt) {
  auto exported = learner::ReadExportedPolicy(ExportSteerPolicy());
  ASSERT_TRUE(exported.ok()) << exported.status();
  ASSERT_TRUE(exported->spec.physics.recorded());
  const PhysicsSettings trained = exported->spec.physics;
  exported->spec.physics = PhysicsSettings{};
  const std::string stamped = TempDir() + "/steer_with_physics.pt";
  auto upgrade = learner::UpgradePolicy(*exported, SpecsOf("5part").wire, stamped);
  ASSERT_TRUE(upgrade.ok()) << upgrade.status();
  EXPECT_FALSE(upgrade->rebuilt);
  EXPECT_TRUE(upgrade->physics_added);
  EXPECT_EQ(upgrade->forward_difference, 0.0);
  auto checkpoint = PolicyCheckpoint::LoadFile(stamped);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_EQ((*checkpoint)->spec().task, "steer");
  EXPECT_EQ((*checkpoint)->spec().physics.ToJson(), trained.ToJson());
  EXPECT_TRUE((*checkpoint)->has_skills());
  EXPECT_FALSE(std::filesystem::exists(stamped + ".upgrade"));

  v1::EnvSpec other_rate = SpecsOf("5part").wire;
  other_rate.mutable_physics()->set_physics_dt(2 * trained.physics_dt);
  exported->spec.physics = trained;
  auto refused = learner::UpgradePolicy(*exported, other_rate, TempDir() + "/steer_refused.pt");
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_FALSE(std::filesystem::exists(TempDir() + "/steer_refused.pt"));
}

// A skills() that returns no [n, parts, embed_dim] leaves forward usable and composition refused.
TEST(SkillExportTest, ABrokenSkillsMethodCostsCompositionOnly) {
  auto bytes = AffinePolicyBytes(PolicySpecForEnv(SpecsOf("5part").env), {}, {});
  ASSERT_TRUE(bytes.ok());
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}};
  std::istringstream in(*bytes, std::ios::binary);
  torch::jit::Module module = torch::jit::load(in, torch::kCPU, extra);
  module.define("def skills(self, obs):\n    return obs\ndef act_with_z(self, obs, z):\n    return self.forward(obs)\n");
  std::ostringstream out(std::ios::binary);
  module.save(out, extra);
  auto checkpoint = PolicyCheckpoint::LoadBytes(out.str());
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  EXPECT_FALSE((*checkpoint)->has_skills());
  EXPECT_THAT(std::string((*checkpoint)->skills_error().message()), HasSubstr("skills() returned a 2-d tensor"));
  std::vector<float> obs = RandomObs(1), actions(69), z(1000);
  EXPECT_TRUE((*checkpoint)->Act(obs.data(), 1, actions.data()).ok());
  EXPECT_EQ((*checkpoint)->Skills(obs.data(), 1, z.data()).code(), absl::StatusCode::kFailedPrecondition);
}

TEST(SkillCompositionTest, InterpolationGoesFromZeroToOne) {
  EXPECT_EQ(InterpolationAlpha(0, 31), 0.0);
  EXPECT_EQ(InterpolationAlpha(15, 31), 0.5);
  EXPECT_EQ(InterpolationAlpha(30, 31), 1.0);
  EXPECT_EQ(InterpolationAlpha(40, 31), 1.0);
  EXPECT_EQ(InterpolationAlpha(0, 1), 1.0);
}

// Per frame of one clip: positions and z (empty on the last frame).
struct Recorded {
  std::vector<std::vector<float>> pos, z;
  std::vector<v1::ClipMetrics> metrics;
};

class SkillRolloutTest : public SimulationServerTest {
 protected:
  v1::RolloutRequest Request(const std::string& checkpoint = Tracker()) {
    v1::RolloutRequest request;
    request.set_checkpoint_bytes(*ReadFileToString(checkpoint, 1 << 30));
    request.set_max_steps_per_clip(kSteps);
    request.set_stream_frames(true);
    return request;
  }
  v1::RolloutRequest Composed(const std::string& base, const std::string& source, const std::string& part,
                              v1::CompositionMode mode) {
    v1::RolloutRequest request = Request();
    request.set_record_skills(true);
    request.mutable_composition()->set_base_clip(base);
    request.mutable_composition()->set_source_clip(source);
    request.mutable_composition()->add_parts(part);
    request.mutable_composition()->set_mode(mode);
    return request;
  }
  Recorded Run(const v1::RolloutRequest& request) {
    Recorded out;
    auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) {
      std::vector<float> pos, z;
      EXPECT_TRUE(ReadFloatTensor(frame.sim_body_pos(), "sim_body_pos", &pos).ok());
      if (frame.has_skill_z()) EXPECT_TRUE(ReadFloatTensor(frame.skill_z(), "skill_z", &z).ok());
      out.pos.push_back(pos);
      out.z.push_back(z);
    });
    EXPECT_TRUE(metrics.ok()) << metrics.status();
    if (metrics.ok()) out.metrics = *metrics;
    return out;
  }
  void ExpectRefused(const v1::RolloutRequest& request, absl::StatusCode code, const std::string& needle) {
    auto result = client_->Rollout(request);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), code) << result.status();
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  }
};

TEST_F(SkillRolloutTest, RecordedZIsUnitPerPartAndTheRolloutIsThePlainOne) {
  v1::RolloutRequest plain = Request();
  plain.add_clips("deepmimic_walk");
  const Recorded forward = Run(plain);
  plain.set_record_skills(true);
  const Recorded split = Run(plain);
  ASSERT_EQ(split.metrics.size(), 1u);
  EXPECT_EQ(split.metrics[0].steps(), forward.metrics[0].steps());
  EXPECT_EQ(split.metrics[0].g_mpjpe_mm(), forward.metrics[0].g_mpjpe_mm());
  EXPECT_EQ(split.pos, forward.pos);
  ASSERT_EQ(split.z.size(), static_cast<size_t>(split.metrics[0].steps() + 1));
  EXPECT_TRUE(split.z.back().empty());  // no action from the last frame
  for (size_t f = 0; f + 1 < split.z.size(); ++f) {
    ASSERT_EQ(split.z[f].size(), static_cast<size_t>(kParts * 32));
    for (int p = 0; p < kParts; ++p) {
      double norm = 0;
      for (int e = 0; e < 32; ++e) norm += split.z[f][p * 32 + e] * split.z[f][p * 32 + e];
      EXPECT_NEAR(std::sqrt(norm), 1.0, 1e-5);
    }
  }
  EXPECT_TRUE(forward.z.front().empty());  // without record_skills
}

TEST_F(SkillRolloutTest, ComposingAClipWithItselfIsThePlainRollout) {
  v1::RolloutRequest plain = Request();
  plain.add_clips("deepmimic_walk");
  const Recorded expected = Run(plain);
  for (v1::CompositionMode mode : {v1::SWAP, v1::INTERPOLATE}) {
    const Recorded composed = Run(Composed("deepmimic_walk", "deepmimic_walk", "R_Arm", mode));
    ASSERT_EQ(composed.metrics.size(), 1u);
    const v1::ClipMetrics& m = composed.metrics[0];
    EXPECT_EQ(m.clip(), "deepmimic_walk");
    EXPECT_EQ(m.steps(), expected.metrics[0].steps());
    EXPECT_EQ(m.success(), expected.metrics[0].success());
    EXPECT_EQ(m.g_mpjpe_mm(), expected.metrics[0].g_mpjpe_mm());
    EXPECT_EQ(m.mpjpe_mm(), expected.metrics[0].mpjpe_mm());
    EXPECT_EQ(composed.pos, expected.pos);
    ASSERT_TRUE(m.has_composition());
    EXPECT_EQ(m.composition().source_clip(), "deepmimic_walk");
    EXPECT_EQ(m.composition().parts(0), "R_Arm");
    EXPECT_EQ(m.composition().source_steps(), m.steps());
    EXPECT_EQ(m.composition().held_steps(), 0);
  }
}

TEST_F(SkillRolloutTest, SwapTakesTheSourcesZAndInterpolationStartsAtTheBase) {
  v1::RolloutRequest plain = Request();
  plain.set_record_skills(true);
  plain.add_clips("deepmimic_walk");
  const Recorded base = Run(plain);
  plain.set_clips(0, "deepmimic_punch");
  const Recorded source = Run(plain);
  const int part = 4;  // R_Arm
  const Recorded swapped = Run(Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::SWAP));
  const int source_steps = source.metrics[0].steps();
  EXPECT_EQ(swapped.metrics[0].composition().source_steps(), source_steps);
  EXPECT_EQ(swapped.metrics[0].composition().source_terminated(), !source.metrics[0].success());
  const int base_steps = swapped.metrics[0].steps();
  EXPECT_EQ(swapped.metrics[0].composition().held_steps(), std::max(0, base_steps - source_steps));
  for (int f = 0; f < base_steps; ++f) {
    const std::vector<float>& from = source.z[std::min(f, source_steps - 1)];
    EXPECT_TRUE(std::equal(from.begin() + part * 32, from.begin() + (part + 1) * 32, swapped.z[f].begin() + part * 32))
        << "frame " << f;
  }
  // The arm's new z changed the motion.
  EXPECT_NE(swapped.pos, base.pos);

  const Recorded blended = Run(Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::INTERPOLATE));
  // alpha 0 at the first step: the first action is the base's own, so are the first two frames.
  EXPECT_EQ(blended.z[0], base.z[0]);
  EXPECT_EQ(blended.pos[1], base.pos[1]);
  EXPECT_NE(blended.pos, base.pos);
  for (size_t f = 0; f + 1 < blended.z.size(); ++f) {
    double norm = 0;
    for (int e = 0; e < 32; ++e) norm += blended.z[f][part * 32 + e] * blended.z[f][part * 32 + e];
    EXPECT_NEAR(std::sqrt(norm), 1.0, 1e-5) << "frame " << f;
  }
}

TEST_F(SkillRolloutTest, BadCompositionsAreRefusedNamingTheField) {
  using absl::StatusCode;
  ExpectRefused(Composed("deepmimic_walk", "deepmimic_punch", "Tail", v1::SWAP), StatusCode::kInvalidArgument,
                "composition.parts[0]: unknown part 'Tail'");
  v1::RolloutRequest twice = Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::SWAP);
  twice.mutable_composition()->add_parts("R_Arm");
  ExpectRefused(twice, StatusCode::kInvalidArgument, "composition.parts[1]");
  v1::RolloutRequest none = Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::SWAP);
  none.mutable_composition()->clear_parts();
  ExpectRefused(none, StatusCode::kInvalidArgument, "composition.parts");
  ExpectRefused(Composed("no_such_clip", "deepmimic_punch", "R_Arm", v1::SWAP), StatusCode::kNotFound,
                "composition.base_clip");
  ExpectRefused(Composed("deepmimic_walk", "no_such_clip", "R_Arm", v1::SWAP), StatusCode::kNotFound,
                "composition.source_clip");
  ExpectRefused(Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", static_cast<v1::CompositionMode>(7)),
                StatusCode::kInvalidArgument, "composition.mode");
  v1::RolloutRequest with_clips = Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::SWAP);
  with_clips.add_clips("deepmimic_walk");
  ExpectRefused(with_clips, StatusCode::kInvalidArgument, "clips");
  // Checkpoints that cannot compose: affine, exported before composition, whole-body.
  v1::RolloutRequest affine = Composed("deepmimic_walk", "deepmimic_punch", "R_Arm", v1::SWAP);
  affine.set_checkpoint_bytes(OpenLoopPolicyBytes());
  ExpectRefused(affine, StatusCode::kFailedPrecondition, "composition: the checkpoint defines no skills()");
  v1::RolloutRequest old = affine;
  old.set_checkpoint_bytes(*ReadFileToString(OldExport(Tracker(), "old_for_server.pt"), 1 << 30));
  ExpectRefused(old, StatusCode::kFailedPrecondition, "modskill-policy-upgrade");
  v1::RolloutRequest record = Request(OldExport(Tracker(), "old_for_record.pt"));
  record.add_clips("deepmimic_walk");
  record.set_record_skills(true);
  ExpectRefused(record, StatusCode::kFailedPrecondition, "record_skills");
  v1::RolloutRequest whole = affine;
  whole.set_checkpoint_bytes(*ReadFileToString(ExportTracker("whole_body.pt", true), 1 << 30));
  ExpectRefused(whole, StatusCode::kFailedPrecondition, "whole-body");
  // A task (steer) policy: its z comes from a task head, not from clips.
  v1::RolloutRequest task = affine;
  task.set_checkpoint_bytes(*ReadFileToString(ExportSteerPolicy(), 1 << 30));
  ExpectRefused(task, StatusCode::kFailedPrecondition, "composition: the checkpoint is a policy for task steer");
}

}  // namespace
}  // namespace modskill
