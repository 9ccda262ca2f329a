#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace lumistage {

// The nearest-rank percentile of `values` (`fraction` 0..1: the smallest value with at least that
// fraction of the values at or below it), NaN when there are none. Reorders `values`.
inline double nearestRankPercentile(std::vector<double>& values, double fraction) {
  if (values.empty()) return std::nan("");
  const size_t k = std::min(values.size() - 1,
                            size_t(std::max(1.0, std::ceil(fraction * double(values.size())))) - 1);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace lumistage
