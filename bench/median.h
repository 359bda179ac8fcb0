// The statistic every benchmark reports: the median of repeated measurements (these machines
// are noisy, and a median ignores the odd slow run). Empty input gives T().
#ifndef MODSKILL_BENCH_MEDIAN_H_
#define MODSKILL_BENCH_MEDIAN_H_

#include <algorithm>
#include <vector>

namespace modskill {

template <typename T>
T Median(std::vector<T> values) {
  if (values.empty()) return T();
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

}  // namespace modskill

#endif  // MODSKILL_BENCH_MEDIAN_H_
