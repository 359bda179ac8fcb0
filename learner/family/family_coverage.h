// How much of a family's parameter range its elites cover (issue 14's bar): probe points spread
// over the free dimensions of the normalized space (constraints stay at 0); a probe is covered
// when an elite whose fitness reaches the acceptance lies within the radius (the elite set's
// replacement radius r = 0.1 by default).
#ifndef MODSKILL_LEARNER_FAMILY_FAMILY_COVERAGE_H_
#define MODSKILL_LEARNER_FAMILY_FAMILY_COVERAGE_H_

#include <cstdint>
#include <vector>

#include "learner/family/elite_set.h"

namespace modskill::learner::family {

struct CoverageConfig {
  double acceptance = 0.1;  // F an elite needs to count (the authors' code admits no elite below 0.1)
  double radius = 0.1;      // normalized units
  int probes = 256;         // evenly spaced with one free dimension, uniform draws with more
  uint64_t seed = 7;        // the draws: the same probes every time
};

// The covered share of the probes, in [0, 1]; 0 for an empty set. `free` has one entry per
// dimension (false: a constraint).
double EliteCoverage(const EliteSet& elites, const std::vector<bool>& free, const CoverageConfig& config = {});

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_FAMILY_COVERAGE_H_
