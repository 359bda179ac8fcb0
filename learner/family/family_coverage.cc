#include "learner/family/family_coverage.h"

#include <algorithm>
#include <random>

namespace modskill::learner::family {
namespace {

std::vector<std::vector<double>> Probes(const std::vector<bool>& free, const CoverageConfig& config) {
  const int free_dims = static_cast<int>(std::count(free.begin(), free.end(), true));
  std::vector<std::vector<double>> probes(config.probes, std::vector<double>(free.size(), 0.0));
  std::mt19937_64 rng(config.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int k = 0; k < config.probes; ++k) {
    for (size_t d = 0; d < free.size(); ++d) {
      if (!free[d]) continue;
      probes[k][d] = free_dims == 1 ? (k + 0.5) / config.probes : uniform(rng);
    }
  }
  return probes;
}

}  // namespace

double EliteCoverage(const EliteSet& elites, const std::vector<bool>& free, const CoverageConfig& config) {
  if (elites.size() == 0 || config.probes < 1) return 0.0;
  // Replacement keeps elites about r apart, so a handful of neighbours holds every one within r.
  constexpr int kNeighbors = 8;
  int covered = 0;
  for (const std::vector<double>& probe : Probes(free, config)) {
    for (const Neighbor& neighbor : elites.Nearest(probe, kNeighbors)) {
      if (neighbor.distance <= config.radius && elites.elite(neighbor.id).fitness >= config.acceptance) {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / config.probes;
}

}  // namespace modskill::learner::family
