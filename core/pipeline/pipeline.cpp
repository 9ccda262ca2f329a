#include "core/pipeline/pipeline.h"

#include <algorithm>

namespace lumistage {

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int64_t wallNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0;
  const size_t at = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + at, values.end());
  return values[at];
}

double eventsPerSecond(const std::vector<double>& times_ns) {
  if (times_ns.size() < 2) return 0;
  const auto [first, last] = std::minmax_element(times_ns.begin(), times_ns.end());
  return *last > *first ? double(times_ns.size() - 1) / ((*last - *first) / 1e9) : 0;
}

}  // namespace lumistage
