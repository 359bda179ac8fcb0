// modskill-policy-average's core (learner/policy_average.h): the averaged file holds the mean of
// every floating-point tensor, runs like any exported policy, and files that cannot be averaged
// are refused with the file named.
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/script.h>
#include <torch/torch.h>

#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/policy_average.h"
#include "learner/policy_export.h"
#include "learner/policy_import.h"
#include "learner/running_mean_std.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/policy_fit.h"
#include "tests/env_specs.h"
#include "tests/test_files.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;

std::string TmpPath(const std::string& name) { return ProcessTempDir("policy_average") + "/" + name; }

// A freshly initialized `small` tracker of `layout_name` (weights from `seed`), exported to `file`.
std::string ExportedTracker(const std::string& layout_name, int seed, const std::string& file) {
  torch::manual_seed(seed);
  auto config = ModelConfig::Preset("small");
  EXPECT_TRUE(config.ok()) << config.status();
  ModSkillPolicy policy(LayoutFromWireSpec(SpecsOf(layout_name).wire), *config);
  RunningMeanStd norm(policy->layout().obs_size);
  norm->Update(torch::randn({32, policy->layout().obs_size}) * (1.0 + seed));
  const std::string path = TmpPath(file);
  const absl::Status exported = ExportPolicy(policy, norm, PolicySpecForEnv(SpecsOf(layout_name).env), path);
  EXPECT_TRUE(exported.ok()) << exported;
  return path;
}

TEST(PolicyAverageTest, AveragedFileHoldsTheMeanAndRuns) {
  const std::vector<std::string> inputs = {ExportedTracker("5part", 1, "a.pt"), ExportedTracker("5part", 2, "b.pt"),
                                           ExportedTracker("5part", 3, "c.pt")};
  const std::string out = TmpPath("mean.pt");
  const absl::Status averaged = AveragePolicies(inputs, out);
  ASSERT_TRUE(averaged.ok()) << averaged;

  std::vector<ExportedPolicy> read;
  for (const std::string& path : inputs) read.push_back(*ReadExportedPolicy(path));
  auto mean = ReadExportedPolicy(out);
  ASSERT_TRUE(mean.ok()) << mean.status();
  EXPECT_EQ(mean->spec.ToJson(), read[0].spec.ToJson());
  ASSERT_EQ(mean->tensors.size(), read[0].tensors.size());
  int differing = 0;
  for (const auto& [name, tensor] : mean->tensors) {
    if (!tensor.is_floating_point()) continue;
    const torch::Tensor expected = (read[0].tensors.at(name) + read[1].tensors.at(name) + read[2].tensors.at(name)) / 3;
    EXPECT_TRUE(torch::allclose(tensor, expected, 1e-6, 1e-6)) << name;
    // (Constant initial values, like log_std and zero output biases, are the same in every input.)
    if (!torch::equal(read[0].tensors.at(name), read[1].tensors.at(name))) {
      ++differing;
      EXPECT_FALSE(torch::equal(tensor, read[0].tensors.at(name))) << name << " was not averaged";
    }
  }
  EXPECT_GT(differing, 10);

  // The server's loader takes it, and its forward differs from every input's.
  auto checkpoint = PolicyCheckpoint::LoadFile(out);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status();
  torch::jit::Module script = torch::jit::load(out), first = torch::jit::load(inputs[0]);
  const torch::Tensor obs = torch::randn({4, mean->spec.obs_size});
  const torch::Tensor actions = script.forward({obs}).toTensor();
  EXPECT_TRUE(actions.isfinite().all().item<bool>());
  EXPECT_GT((actions - first.forward({obs}).toTensor()).abs().max().item<float>(), 1e-4);
}

TEST(PolicyAverageTest, RefusesWhatCannotBeAveraged) {
  const std::string a = ExportedTracker("5part", 1, "r_a.pt"), b = ExportedTracker("5part", 2, "r_b.pt");
  const std::string other_layout = ExportedTracker("3part", 1, "r_3part.pt");
  const std::string out = TmpPath("refused.pt");
  EXPECT_THAT(AveragePolicies({a}, out).message(), HasSubstr("at least two"));
  EXPECT_THAT(AveragePolicies({a, other_layout}, out).message(), HasSubstr(other_layout));
  const std::string not_a_policy = TmpPath("not_a_policy.pt");
  ASSERT_TRUE(WriteFileAtomically(not_a_policy, "hello").ok());
  EXPECT_THAT(AveragePolicies({a, not_a_policy}, out).message(), HasSubstr(not_a_policy));
  EXPECT_THAT(AveragePolicies({a, TmpPath("missing.pt")}, out).message(), HasSubstr("missing.pt"));
  EXPECT_FALSE(std::filesystem::exists(out)) << "nothing is written when the inputs are refused";
  EXPECT_TRUE(AveragePolicies({a, b}, out).ok());
}

}  // namespace
}  // namespace modskill::learner
