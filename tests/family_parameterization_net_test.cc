// The parameterization network P(a) -> {(d_t, tau_t)} (learner/family/parameterization_net.h):
// it fits a known function of (a, phase), and trains from an elite set.
#include "learner/family/parameterization_net.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace modskill::learner::family {
namespace {

// A known family: d = a0 sin(2 pi phase) + 0.5 a1, tau = 0.3 (a0 - a1) phase.
torch::Tensor Known(const torch::Tensor& a, const torch::Tensor& phase) {
  const torch::Tensor d = a.select(1, 0) * torch::sin(2 * M_PI * phase) + 0.5 * a.select(1, 1);
  const torch::Tensor tau = 0.3 * (a.select(1, 0) - a.select(1, 1)) * phase;
  return torch::stack({d, tau}, 1);
}

TEST(FamilyParameterizationNetTest, ShapesAtForward) {
  ParameterizationNet net(ParameterizationNetConfig{3, 5, {16, 16}});
  EXPECT_EQ(net->forward(torch::rand({7, 3}), torch::rand({7})).sizes(), torch::IntArrayRef({7, 5}));
  absl::StatusOr<torch::Tensor> traj = net->Trajectory({0.1, 0.2, 0.3}, 11);
  ASSERT_TRUE(traj.ok());
  EXPECT_EQ(traj->sizes(), torch::IntArrayRef({11, 5}));
  EXPECT_EQ(net->Trajectory({0.1}, 11).status().code(), absl::StatusCode::kInvalidArgument);
  ParameterizationNet paper(ParameterizationNetConfig{2, 4});  // default hidden 2 x 512
  EXPECT_EQ(paper->parameters().size(), 6u);
  EXPECT_EQ(paper->parameters()[0].size(0), 512);
}

TEST(FamilyParameterizationNetTest, FitsAKnownFunction) {
  torch::manual_seed(0);
  ParameterizationNet net(ParameterizationNetConfig{2, 2, {64, 64}});
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(3e-3));
  const torch::Tensor a = torch::rand({4096, 2}), phase = torch::rand({4096});
  const ParameterizationData data{a, phase, Known(a, phase)};
  const torch::Tensor test_a = torch::rand({512, 2}), test_phase = torch::rand({512});
  const torch::Tensor test_target = Known(test_a, test_phase);
  const double before = torch::mse_loss(net->forward(test_a, test_phase), test_target).item<double>();
  absl::StatusOr<double> train_loss = FitParameterization(net, adam, data, FitOptions{40, 128, 1});
  ASSERT_TRUE(train_loss.ok()) << train_loss.status();
  torch::NoGradGuard no_grad;
  const double after = torch::mse_loss(net->forward(test_a, test_phase), test_target).item<double>();
  // The targets' variance is ~0.2; the fit must get close on points it never saw.
  EXPECT_LT(after, 2e-3) << "before " << before;
  EXPECT_LT(after, before / 50);
  EXPECT_LT(*train_loss, 2e-3);
}

TEST(FamilyParameterizationNetTest, TrainsFromElites) {
  torch::manual_seed(1);
  const int64_t frames = 16;
  EliteSet elites(2, frames, 2);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int i = 0; i < 400; ++i) {
    const std::vector<double> a = {unit(rng), unit(rng)};
    const torch::Tensor av = torch::tensor(a, torch::kFloat32).unsqueeze(0).expand({frames, 2});
    ASSERT_TRUE(elites.Offer(a, unit(rng), Known(av, torch::linspace(0, 1, frames))).ok());
  }
  absl::StatusOr<ParameterizationData> data = EliteTrainingData(elites);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(data->params.size(0), elites.size() * frames);
  ParameterizationNet net(ParameterizationNetConfig{2, 2, {64, 64}});
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(3e-3));
  ASSERT_TRUE(FitParameterization(net, adam, *data, FitOptions{60, 64, 2}).ok());
  torch::NoGradGuard no_grad;
  absl::StatusOr<torch::Tensor> traj = net->Trajectory({0.4, 0.6}, frames);
  ASSERT_TRUE(traj.ok());
  const torch::Tensor want = Known(torch::tensor({0.4, 0.6}).unsqueeze(0).expand({frames, 2}), torch::linspace(0, 1, frames));
  EXPECT_LT((*traj - want).abs().max().item<double>(), 0.1);
}

TEST(FamilyParameterizationNetTest, RefusesMismatchedData) {
  ParameterizationNet net(ParameterizationNetConfig{2, 2, {8}});
  torch::optim::Adam adam(net->parameters());
  const auto code = [&](ParameterizationData d, FitOptions o = {}) { return FitParameterization(net, adam, d, o).status(); };
  EXPECT_THAT(std::string(code({torch::rand({4, 3}), torch::rand({4}), torch::rand({4, 2})}).message()), ::testing::HasSubstr("params must be"));
  EXPECT_THAT(std::string(code({torch::rand({4, 2}), torch::rand({5}), torch::rand({4, 2})}).message()), ::testing::HasSubstr("phase must be [4]"));
  EXPECT_THAT(std::string(code({torch::rand({4, 2}), torch::rand({4}), torch::rand({4, 3})}).message()), ::testing::HasSubstr("targets must be [4, 2]"));
  EXPECT_THAT(std::string(code({torch::rand({4, 2}), torch::full({4}, NAN), torch::rand({4, 2})}).message()), ::testing::HasSubstr("non-finite"));
  EXPECT_THAT(std::string(code({torch::rand({4, 2}), torch::rand({4}), torch::rand({4, 2})}, {0, 8, 0}).message()), ::testing::HasSubstr("epochs 0"));
  EXPECT_EQ(EliteTrainingData(EliteSet(2, 16, 2)).status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace modskill::learner::family
