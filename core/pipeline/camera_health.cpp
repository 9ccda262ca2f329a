#include "core/pipeline/camera_health.h"

#include <fmt/format.h>

namespace lumistage {

const char* healthStateName(HealthState state) {
  switch (state) {
    case HealthState::kStreaming:
      return "streaming";
    case HealthState::kLate:
      return "late";
    case HealthState::kLost:
      return "lost";
    case HealthState::kUnknown:
      break;
  }
  return "unknown";
}

HealthVerdict classifyHealth(const HealthInput& in, const HealthThresholds& t) {
  if (in.process_exited) return {HealthState::kLost, "node process exited: no frames"};
  if (in.silent_ms < 0) return {HealthState::kUnknown, "not heard from yet"};
  if (in.silent_ms >= t.lost_after_ms) {
    return {HealthState::kLost,
            fmt::format("nothing for {:.1f} s: unplugged, stopped or off the network",
                        in.silent_ms / 1000)};
  }
  if (in.silent_ms >= t.late_after_ms)
    return {HealthState::kLate, fmt::format("nothing for {:.0f} ms", in.silent_ms)};
  if (!in.last_error.empty()) return {HealthState::kLate, "error: " + in.last_error};
  if (in.expected_rate_hz > 0 && in.frame_rate_hz > 0 &&
      in.frame_rate_hz < t.min_rate_share * in.expected_rate_hz) {
    return {HealthState::kLate,
            fmt::format("{:.1f} fps of {:.0f} expected", in.frame_rate_hz, in.expected_rate_hz)};
  }
  if (in.dropped_recently > 0) {
    return {HealthState::kLate, fmt::format("{} frame{} dropped", in.dropped_recently,
                                            in.dropped_recently > 1 ? "s" : "")};
  }
  return {HealthState::kStreaming, in.frame_rate_hz > 0
                                       ? fmt::format("streaming at {:.1f} fps", in.frame_rate_hz)
                                       : std::string("streaming")};
}

void HealthHistory::add(const std::string& key, double time_s, double value) {
  std::deque<Sample>& s = series_[key];
  s.push_back({time_s, value});
  while (s.size() > capacity_) s.pop_front();
}

const std::deque<HealthHistory::Sample>& HealthHistory::samples(const std::string& key) const {
  static const std::deque<Sample> kEmpty;
  const auto it = series_.find(key);
  return it == series_.end() ? kEmpty : it->second;
}

std::vector<std::string> HealthHistory::keys() const {
  std::vector<std::string> out;
  for (const auto& [key, s] : series_) out.push_back(key);
  return out;
}

}  // namespace lumistage
