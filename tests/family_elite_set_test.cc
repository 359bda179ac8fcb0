// The k-d tree against brute force, the elite set's replacement rule, and the elites'
// bootstrap blend (learner/family/kd_tree.h, elite_set.h, elite_bootstrap.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "learner/family/elite_bootstrap.h"
#include "learner/family/elite_set.h"
#include "learner/family/kd_tree.h"

namespace modskill::learner::family {
namespace {

double Dist(const std::vector<double>& a, const std::vector<double>& b) {
  double d2 = 0;
  for (size_t i = 0; i < a.size(); ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(d2);
}

TEST(FamilyKdTreeTest, MatchesBruteForceThroughInsertsAndRemovals) {
  for (int dims : {1, 2, 5}) {
    std::mt19937_64 rng(dims);
    std::uniform_real_distribution<double> unit(0, 1);
    KdTree tree(dims);
    std::vector<std::vector<double>> points;
    std::vector<bool> live;
    for (int i = 0; i < 3000; ++i) {
      std::vector<double> p(dims);
      for (double& x : p) x = dims == 1 ? std::round(unit(rng) * 50) / 50 : unit(rng);  // 1-D: many ties
      ASSERT_TRUE(tree.Insert(i, p).ok());
      points.push_back(p);
      live.push_back(true);
      if (i % 3 == 2) {  // remove a random live point now and then, forcing rebuilds
        const int victim = static_cast<int>(unit(rng) * i);
        EXPECT_EQ(tree.Remove(victim), static_cast<bool>(live[victim]));
        live[victim] = false;
      }
    }
    EXPECT_EQ(tree.size(), std::count(live.begin(), live.end(), true));
    for (int q = 0; q < 50; ++q) {
      std::vector<double> query(dims);
      for (double& x : query) x = unit(rng);
      std::vector<double> brute;
      for (size_t i = 0; i < points.size(); ++i) {
        if (live[i]) brute.push_back(Dist(points[i], query));
      }
      std::sort(brute.begin(), brute.end());
      const std::vector<Neighbor> nearest = tree.Nearest(query, 7);
      ASSERT_EQ(nearest.size(), 7u);
      for (int k = 0; k < 7; ++k) EXPECT_DOUBLE_EQ(nearest[k].distance, brute[k]);
      const double r = 0.1;
      const std::vector<Neighbor> within = tree.WithinRadius(query, r);
      EXPECT_EQ(within.size(), static_cast<size_t>(std::upper_bound(brute.begin(), brute.end(), r) - brute.begin()));
      for (const Neighbor& n : within) EXPECT_TRUE(live[n.id]);
    }
  }
}

TEST(FamilyKdTreeTest, RefusesBadPoints) {
  KdTree tree(2);
  ASSERT_TRUE(tree.Insert(1, {0.5, 0.5}).ok());
  EXPECT_EQ(tree.Insert(1, {0.1, 0.1}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(tree.Insert(2, {0.1}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(tree.Insert(3, {0.1, NAN}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(tree.Remove(7));
  EXPECT_TRUE(tree.Nearest({0, 0}, 0).empty());
}

torch::Tensor Traj(float value) { return torch::full({4, 2}, value); }

TEST(FamilyEliteSetTest, FitterEpisodeReplacesNeighboursWithinRadius) {
  EliteSet elites(2, 4, 2);  // r = 0.1
  ASSERT_TRUE(elites.Offer({0.50, 0.50}, 0.6, Traj(1)).value());
  ASSERT_TRUE(elites.Offer({0.57, 0.50}, 0.4, Traj(2)).value() == false);  // within r of a fitter elite
  ASSERT_TRUE(elites.Offer({0.62, 0.50}, 0.4, Traj(2)).value());           // 0.12 away: its own region
  EXPECT_EQ(elites.size(), 2);
  // 0.06 from both and fitter than both: replaces both
  ASSERT_TRUE(elites.Offer({0.56, 0.50}, 0.7, Traj(3)).value());
  EXPECT_EQ(elites.size(), 1);
  const Elite& e = elites.elite(elites.Nearest({0.5, 0.5}, 1)[0].id);
  EXPECT_DOUBLE_EQ(e.fitness, 0.7);
  EXPECT_TRUE(torch::equal(e.trajectory, Traj(3)));
  // an equally fit episode does not displace an elite
  EXPECT_FALSE(elites.Offer({0.56, 0.55}, 0.7, Traj(4)).value());
  EXPECT_EQ(elites.Ids().size(), 1u);
}

TEST(FamilyEliteSetTest, RefusesBadOffers) {
  EliteSet elites(2, 4, 2);
  EXPECT_EQ(elites.Offer({0.5}, 1, Traj(0)).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(elites.Offer({0.5, 1.2}, 1, Traj(0)).status().message()), ::testing::HasSubstr("param 1 = 1.2"));
  EXPECT_EQ(elites.Offer({0.5, 0.5}, NAN, Traj(0)).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(elites.Offer({0.5, 0.5}, 1, torch::zeros({3, 2})).status().message()), ::testing::HasSubstr("[4, 2]"));
  EXPECT_EQ(elites.size(), 0);
}

TEST(FamilyEliteBootstrapTest, BlendsTheNearestFiveByFitnessAndDistance) {
  EliteSet elites(1, 4, 2);
  // the 5 nearest to a = 0.5 first; 0.05 and 0.95 are farther and left out of the blend
  const std::vector<std::pair<double, double>> at_fitness = {{0.2, 1.0}, {0.35, 0.5}, {0.5, 0.8}, {0.65, 0.9},
                                                             {0.8, 0.3}, {0.05, 0.9}, {0.95, 0.9}};
  for (size_t i = 0; i < at_fitness.size(); ++i) {
    ASSERT_TRUE(elites.Offer({at_fitness[i].first}, at_fitness[i].second, Traj(static_cast<float>(i))).value());
  }
  const double a = 0.5, s2 = 0.28 * 0.28;
  double num = 0, den = 0;
  for (size_t i = 0; i < 5; ++i) {
    const double d = at_fitness[i].first - a;
    const double w = at_fitness[i].second * std::exp(-d * d / s2);
    num += w * static_cast<double>(i);
    den += w;
  }
  absl::StatusOr<torch::Tensor> blend = BootstrapTrajectory(elites, {a});
  ASSERT_TRUE(blend.ok()) << blend.status();
  ASSERT_EQ(blend->sizes(), torch::IntArrayRef({4, 2}));
  EXPECT_NEAR((*blend)[2][1].item<double>(), num / den, 1e-5);
  // k = 1 is the nearest elite's own trajectory
  absl::StatusOr<torch::Tensor> one = BootstrapTrajectory(elites, {0.68}, {1, 0.28});
  ASSERT_TRUE(one.ok());
  EXPECT_TRUE(torch::allclose(*one, Traj(3)));
}

TEST(FamilyEliteBootstrapTest, RefusesEmptyOrWeightlessSets) {
  EliteSet elites(1, 4, 2);
  EXPECT_EQ(BootstrapTrajectory(elites, {0.5}).status().code(), absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(elites.Offer({0.5}, 0.0, Traj(1)).value());
  EXPECT_EQ(BootstrapTrajectory(elites, {0.5}).status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(BootstrapTrajectory(elites, {0.5, 0.5}).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(BootstrapTrajectory(elites, {0.5}, {0, 0.28}).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace modskill::learner::family
