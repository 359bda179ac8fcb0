// A kernel density over the parameters the curriculum has visited (Lee et al. 2021; DESIGN.md
// section 4), in normalized parameter space, normalized to [0, 1] so that the curriculum's
// thresholds (explore where it is in [0.2, 0.8]) do not depend on how many episodes ran:
//   rho(a) = min(1, sum_i exp(-|a - a_i|^2 / (2 h^2)) / m)
// i.e. the Gaussian kernel sum in units of m visits at a itself. 0 is unvisited, 1 is covered:
// at least m visits' worth within about a bandwidth h. Kernels are cut at 3 h (their tail there
// is exp(-4.5) = 1 %), so an evaluation is a k-d tree radius query.
#ifndef MODSKILL_LEARNER_FAMILY_PARAMETER_DENSITY_H_
#define MODSKILL_LEARNER_FAMILY_PARAMETER_DENSITY_H_

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/types/span.h"
#include "learner/family/kd_tree.h"

namespace modskill::learner::family {

struct DensityConfig {
  double bandwidth = 0.05;  // h, normalized units: 20 kernel widths across a range
  double saturation = 5;    // m: visits' worth of kernel mass that counts as fully covered
};

class ParameterDensity {
 public:
  ParameterDensity(int dims, DensityConfig config = {}) : config_(config), tree_(dims) {}

  // INVALID_ARGUMENT for a point of the wrong size or outside [0, 1].
  absl::Status Add(absl::Span<const double> params);
  // rho(a) in [0, 1]; `params` has dims() values.
  double Evaluate(absl::Span<const double> params) const;

  int dims() const { return tree_.dims(); }
  int64_t size() const { return static_cast<int64_t>(points_.size()); }
  const std::vector<double>& point(int64_t i) const { return points_[i]; }

 private:
  DensityConfig config_;
  KdTree tree_;
  std::vector<std::vector<double>> points_;
};

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_PARAMETER_DENSITY_H_
