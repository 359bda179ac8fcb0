// The parameter curriculum (learner/family/parameter_density.h, parameter_curriculum.h): the
// density's normalization, exploration at the visited region's edge, refinement by MCMC toward
// low values, the switch on the exploration rate, and determinism. Statistical checks use fixed
// seeds and margins a wrong sampler cannot meet by chance.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "learner/family/parameter_curriculum.h"

namespace modskill::learner::family {
namespace {

ParamSpace Space2() { return ParamSpace::Create({{"gravity", 4, 14}, {"leg_scale", 0.8, 1.2}}).value(); }

// Visits on a grid of spacing 0.02 wherever `keep` holds.
template <typename Keep>
void VisitGrid(ParameterCurriculum& c, Keep keep) {
  for (int i = 0; i <= 50; ++i) {
    for (int j = 0; j <= 50; ++j) {
      const std::vector<double> a = {i / 50.0, j / 50.0};
      if (keep(a)) ASSERT_TRUE(c.AddVisited(a).ok());
    }
  }
}

std::vector<double> Constant(const std::vector<std::vector<double>>& a) { return std::vector<double>(a.size(), 1.0); }

TEST(FamilyCurriculumTest, DensityIsNormalizedToVisits) {
  ParameterDensity density(2);  // h 0.05, m 5
  EXPECT_EQ(density.Evaluate({0.5, 0.5}), 0.0);
  ASSERT_TRUE(density.Add({0.5, 0.5}).ok());
  EXPECT_DOUBLE_EQ(density.Evaluate({0.5, 0.5}), 0.2);                        // one visit of m = 5
  EXPECT_NEAR(density.Evaluate({0.55, 0.5}), 0.2 * std::exp(-0.5), 1e-12);   // one bandwidth away
  EXPECT_EQ(density.Evaluate({0.7, 0.5}), 0.0);                               // beyond the 3 h cut
  for (int i = 0; i < 9; ++i) ASSERT_TRUE(density.Add({0.5, 0.5}).ok());
  EXPECT_EQ(density.Evaluate({0.5, 0.5}), 1.0);                               // saturated
  EXPECT_EQ(density.Add({0.5, 1.5}).code(), absl::StatusCode::kInvalidArgument);
}

TEST(FamilyCurriculumTest, ExplorationSamplesTheVisitedRegionsEdge) {
  auto c = ParameterCurriculum::Create(Space2(), {}, 7);
  ASSERT_TRUE(c.ok());
  const auto center_distance = [](const std::vector<double>& a) { return std::hypot(a[0] - 0.3, a[1] - 0.3); };
  VisitGrid(*c, [&](const std::vector<double>& a) { return center_distance(a) <= 0.15; });
  const CurriculumBatch batch = c->SampleExploration(200);
  EXPECT_EQ(batch.in_band, 200);
  int ours = 0;
  for (const std::vector<double>& a : batch.params) {
    const double rho = c->density().Evaluate(a);
    ours += rho >= 0.2 && rho <= 0.8;
    EXPECT_GT(center_distance(a), 0.08);  // not deep inside
    EXPECT_LT(center_distance(a), 0.30);  // not far out
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int uniform = 0;
  for (int i = 0; i < 20000; ++i) {
    const double rho = c->density().Evaluate({unit(rng), unit(rng)});
    uniform += rho >= 0.2 && rho <= 0.8;
  }
  // A uniform sampler lands in the band a few % of the time; exploration always does.
  EXPECT_EQ(ours, 200);
  EXPECT_LT(uniform / 20000.0, 0.15);
}

TEST(FamilyCurriculumTest, RefinementConcentratesWhereValueIsBelowMean) {
  CurriculumConfig config;
  config.mcmc_steps = 200;
  auto c = ParameterCurriculum::Create(Space2(), config, 3);
  ASSERT_TRUE(c.ok());
  VisitGrid(*c, [](const std::vector<double>&) { return true; });  // all of [0, 1]^2 covered
  // V = 1 + 0.5 (a0 - 0.5): mu = 1, so p(a) ~ exp(-5 a0), a truncated exponential in a0:
  // P(a0 < 0.5) = (1 - e^-2.5) / (1 - e^-5) = 0.924, E[a0] = 1/5 - e^-5 / (1 - e^-5) = 0.193.
  const ValueFunction value = [](const std::vector<std::vector<double>>& a) {
    std::vector<double> v;
    for (const auto& x : a) v.push_back(1 + 0.5 * (x[0] - 0.5));
    return v;
  };
  absl::StatusOr<CurriculumBatch> batch = c->SampleRefinement(400, value);
  ASSERT_TRUE(batch.ok()) << batch.status();
  ASSERT_EQ(batch->params.size(), 400u);
  EXPECT_EQ(batch->mode, CurriculumMode::kRefinement);
  double low = 0, mean0 = 0, mean1 = 0;
  for (const auto& a : batch->params) {
    low += a[0] < 0.5;
    mean0 += a[0] / 400;
    mean1 += a[1] / 400;
  }
  // Uniform would give 0.5 (sd 0.025 over 400), the target 0.924.
  EXPECT_GT(low / 400, 0.85);
  EXPECT_NEAR(mean0, 0.193, 0.04);
  EXPECT_NEAR(mean1, 0.5, 0.06);  // V does not depend on a1
}

TEST(FamilyCurriculumTest, RefinementStaysInTheHeavilyVisitedRegion) {
  auto c = ParameterCurriculum::Create(Space2(), {}, 5);
  ASSERT_TRUE(c.ok());
  VisitGrid(*c, [](const std::vector<double>& a) { return a[0] <= 0.5; });
  absl::StatusOr<CurriculumBatch> batch = c->SampleRefinement(200, Constant);
  ASSERT_TRUE(batch.ok()) << batch.status();
  ASSERT_EQ(batch->params.size(), 200u);
  double mean1 = 0;
  for (const auto& a : batch->params) {
    EXPECT_GE(c->density().Evaluate(a), 0.8);
    EXPECT_LT(a[0], 0.58);  // the grid ends at 0.5; its kernels keep rho >= 0.8 about 1.3 h beyond
    mean1 += a[1] / 200;
  }
  EXPECT_NEAR(mean1, 0.5, 0.08);  // a flat V: spread over the region, not stuck at the starts
}

TEST(FamilyCurriculumTest, SwitchesOnTheExplorationRate) {
  auto c = ParameterCurriculum::Create(Space2(), {}, 1);  // min rate 0.05, one refinement batch
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->NextBatch(Constant).status().code(), absl::StatusCode::kFailedPrecondition);  // nothing visited
  VisitGrid(*c, [](const std::vector<double>& a) { return a[0] <= 0.4 && a[1] <= 0.4; });
  absl::StatusOr<CurriculumBatch> batch = c->NextBatch(Constant);
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->mode, CurriculumMode::kExploration);
  EXPECT_EQ(batch->params.size(), 20u);  // 20 parameters x 30 episodes
  EXPECT_EQ(batch->episodes_per_param, 30);
  ASSERT_TRUE(c->ReportBatch(batch->mode, 60, 600).ok());  // rate 0.1: keep exploring
  EXPECT_EQ(c->mode(), CurriculumMode::kExploration);
  ASSERT_TRUE(c->ReportBatch(CurriculumMode::kExploration, 12, 600).ok());  // rate 0.02: refine
  EXPECT_EQ(c->mode(), CurriculumMode::kRefinement);
  EXPECT_DOUBLE_EQ(c->exploration_rate(), 0.02);
  batch = c->NextBatch(Constant);
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->mode, CurriculumMode::kRefinement);
  EXPECT_EQ(batch->params.size(), 20u);
  ASSERT_TRUE(c->ReportBatch(batch->mode, 0, 600).ok());
  EXPECT_EQ(c->mode(), CurriculumMode::kExploration);
  EXPECT_EQ(c->ReportBatch(CurriculumMode::kExploration, 7, 5).code(), absl::StatusCode::kInvalidArgument);
}

TEST(FamilyCurriculumTest, RefinementWithoutACoveredRegionExplores) {
  auto c = ParameterCurriculum::Create(Space2(), {}, 1);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE(c->AddVisited({0.5, 0.5}).ok());  // density 0.2 at most: nothing heavily visited
  ASSERT_TRUE(c->ReportBatch(CurriculumMode::kExploration, 0, 600).ok());
  ASSERT_EQ(c->mode(), CurriculumMode::kRefinement);
  absl::StatusOr<CurriculumBatch> batch = c->NextBatch(Constant);
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->mode, CurriculumMode::kExploration);
  // the band is empty around a single visit (rho <= 0.2 only at the point): nearest draws
  EXPECT_EQ(batch->params.size(), 20u);
}

TEST(FamilyCurriculumTest, DeterministicForASeedAndConstraintsStayZero) {
  const ParamSpace space = ParamSpace::Create({{"gravity", 4, 14}, {"leg_scale", 1.1, 1.1}}).value();
  const auto run = [&](uint64_t seed) {
    auto c = ParameterCurriculum::Create(space, {}, seed);
    for (int i = 0; i <= 20; ++i) EXPECT_TRUE(c->AddVisited({0.3 + i / 100.0, 0}).ok());
    return c->NextBatch(Constant).value().params;
  };
  const auto a = run(9), b = run(9), other = run(10);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, other);
  for (const auto& p : a) EXPECT_EQ(p[1], 0.0);
}

TEST(FamilyCurriculumTest, RefusesBadConfigsAndValues) {
  CurriculumConfig config;
  config.explore_density_lo = 0.9;
  EXPECT_THAT(std::string(ParameterCurriculum::Create(Space2(), config, 0).status().message()),
              ::testing::HasSubstr("explore_density_lo 0.9"));
  config = {};
  config.value_k = 0;
  EXPECT_THAT(std::string(ParameterCurriculum::Create(Space2(), config, 0).status().message()), ::testing::HasSubstr("value_k 0"));
  auto c = ParameterCurriculum::Create(Space2(), {}, 0);
  VisitGrid(*c, [](const std::vector<double>&) { return true; });
  const ValueFunction short_values = [](const std::vector<std::vector<double>>&) { return std::vector<double>{1.0}; };
  EXPECT_EQ(c->SampleRefinement(20, short_values).status().code(), absl::StatusCode::kInvalidArgument);
  const ValueFunction zero = [](const std::vector<std::vector<double>>& a) { return std::vector<double>(a.size(), 0.0); };
  EXPECT_EQ(c->SampleRefinement(20, zero).status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace modskill::learner::family
