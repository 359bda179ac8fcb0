// The elite set's k-d tree (learner/family/kd_tree.h) at the sizes a family run reaches:
// 10^4 and 10^5 points of 1 to 8 normalized parameters, uniform in the unit cube. Per size and
// dims: inserts/s (the tree grown from empty, rebuilds included), removals/s, k = 5 nearest
// queries/s (the bootstrap) beside a linear scan's for scale, radius queries/s at r = 0.1 (the
// elite set's replacement test) with the mean hits per query, and EliteSet::Offer/s on top (a
// [1, 1] trajectory, so the tree and the replacement dominate). Each figure is the median of
// --repeats runs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "bench/median.h"
#include "learner/family/elite_set.h"
#include "learner/family/kd_tree.h"

ABSL_FLAG(int, repeats, 3, "runs per figure (the median is reported)");
ABSL_FLAG(int, queries, 20000, "queries per run");

namespace modskill::learner::family {
namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Rates {
  double insert = 0, remove = 0, nearest = 0, scan = 0, radius = 0, radius_hits = 0, offer = 0;
};

Rates RunOnce(int n, int dims, int queries, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<double> points(static_cast<size_t>(n) * dims), probes(static_cast<size_t>(queries) * dims);
  for (double& x : points) x = unit(rng);
  for (double& x : probes) x = unit(rng);
  const auto point = [&](int i) { return absl::MakeConstSpan(&points[static_cast<size_t>(i) * dims], dims); };
  const auto probe = [&](int i) { return absl::MakeConstSpan(&probes[static_cast<size_t>(i) * dims], dims); };
  Rates rates;
  KdTree tree(dims);
  auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) (void)tree.Insert(i, point(i));
  rates.insert = n / Seconds(start);
  start = std::chrono::steady_clock::now();
  size_t found = 0;
  for (int q = 0; q < queries; ++q) found += tree.Nearest(probe(q), 5).size();
  rates.nearest = queries / Seconds(start);
  // The linear scan the tree must beat: every distance, then the 5 smallest.
  const int scans = std::max(10, queries / 10);
  std::vector<double> d2(n);
  start = std::chrono::steady_clock::now();
  for (int q = 0; q < scans; ++q) {
    for (int i = 0; i < n; ++i) {
      double sum = 0;
      for (int j = 0; j < dims; ++j) sum += (point(i)[j] - probe(q)[j]) * (point(i)[j] - probe(q)[j]);
      d2[i] = sum;
    }
    std::partial_sort(d2.begin(), d2.begin() + 5, d2.end());
    found += d2[0] >= 0;
  }
  rates.scan = scans / Seconds(start);
  // Dense low-dim sets return thousands of hits per r = 0.1 query: fewer of those queries, so
  // that hits stay under ~2e7 per run.
  const double expected_hits = n * std::pow(M_PI, dims / 2.0) / std::tgamma(dims / 2.0 + 1) * std::pow(0.1, dims);
  const int radius_queries = std::max(100, std::min(queries, static_cast<int>(2e7 / std::max(1.0, expected_hits))));
  start = std::chrono::steady_clock::now();
  found = 0;
  for (int q = 0; q < radius_queries; ++q) found += tree.WithinRadius(probe(q), 0.1).size();
  rates.radius = radius_queries / Seconds(start);
  rates.radius_hits = static_cast<double>(found) / radius_queries;
  start = std::chrono::steady_clock::now();
  for (int i = 0; i < n / 2; ++i) tree.Remove(2 * i);
  rates.remove = (n / 2) / Seconds(start);
  EliteSet elites(dims, 1, 1);
  const torch::Tensor trajectory = torch::zeros({1, 1});
  start = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) (void)elites.Offer(point(i), unit(rng), trajectory);
  rates.offer = n / Seconds(start);
  return rates;
}

void Report(int n, int dims) {
  std::vector<double> insert, remove, nearest, scan, radius, hits, offer;
  for (int r = 0; r < absl::GetFlag(FLAGS_repeats); ++r) {
    const Rates rates = RunOnce(n, dims, absl::GetFlag(FLAGS_queries), 17 + r);
    insert.push_back(rates.insert);
    remove.push_back(rates.remove);
    nearest.push_back(rates.nearest);
    scan.push_back(rates.scan);
    radius.push_back(rates.radius);
    hits.push_back(rates.radius_hits);
    offer.push_back(rates.offer);
  }
  std::printf("| %6d | %d | %9.0f | %9.0f | %9.0f | %7.0f | %9.0f | %8.1f | %9.0f |\n", n, dims, Median(insert),
              Median(remove), Median(nearest), Median(scan), Median(radius), Median(hits), Median(offer));
}

}  // namespace
}  // namespace modskill::learner::family

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  torch::set_num_threads(1);
  std::printf("| points | dims | inserts/s | removes/s | 5-NN/s | scan 5-NN/s | r=0.1 queries/s | hits/query | Offer/s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (int n : {10000, 100000}) {
    for (int dims : {1, 2, 4, 8}) modskill::learner::family::Report(n, dims);
  }
  return 0;
}
