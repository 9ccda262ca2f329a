#pragma once

#include <deque>
#include <map>
#include <string>
#include <vector>

namespace lumistage {

// A camera's or node's state as a technician sees it.
enum class HealthState { kUnknown, kStreaming, kLate, kLost };

const char* healthStateName(HealthState state);  // "unknown", "streaming", "late", "lost"

// When a source counts as late or lost. A node sends several messages a frame (silhouettes,
// statistics, partial images) and a heartbeat four times a second, so half a second of silence is
// many missed frames: late; a second of it: lost (the coordinator's lost_after). A node process
// that exited is lost at once.
struct HealthThresholds {
  double late_after_ms = 500;
  double lost_after_ms = 1000;
  double min_rate_share = 0.75;  // a frame rate below this share of the expected one: late
};

// What is known of a camera or node now.
struct HealthInput {
  double silent_ms = -1;  // since its last message; < 0: never heard from
  bool process_exited = false;
  double frame_rate_hz = 0;      // measured; 0: not reported
  double expected_rate_hz = 0;   // 0: no expectation
  int64_t dropped_recently = 0;  // frames dropped since the previous look
  std::string last_error;
};

struct HealthVerdict {
  HealthState state = HealthState::kUnknown;
  std::string words;  // the problem (or its absence) in words, for the user
};

HealthVerdict classifyHealth(const HealthInput& input, const HealthThresholds& thresholds = {});

// The recent history of a few figures per camera (frame rate, latency...), for plots: at most
// `capacity` samples each, oldest first.
class HealthHistory {
 public:
  explicit HealthHistory(size_t capacity = 240) : capacity_(capacity) {}
  void add(const std::string& key, double time_s, double value);
  struct Sample {
    double time_s, value;
  };
  const std::deque<Sample>& samples(const std::string& key) const;
  std::vector<std::string> keys() const;
  void clear() { series_.clear(); }

 private:
  size_t capacity_;
  std::map<std::string, std::deque<Sample>> series_;
};

}  // namespace lumistage
