#include "core/pipeline/camera_health.h"

#include <gtest/gtest.h>

namespace lumistage {
namespace {

TEST(CameraHealth, ClassifiesBySilenceRateAndErrors) {
  HealthInput in;
  EXPECT_EQ(classifyHealth(in).state, HealthState::kUnknown);
  in.silent_ms = 20;
  in.frame_rate_hz = 24.8;
  in.expected_rate_hz = 25;
  HealthVerdict v = classifyHealth(in);
  EXPECT_EQ(v.state, HealthState::kStreaming);
  EXPECT_NE(v.words.find("24.8 fps"), std::string::npos) << v.words;

  in.frame_rate_hz = 12;  // half the expected rate
  v = classifyHealth(in);
  EXPECT_EQ(v.state, HealthState::kLate);
  EXPECT_NE(v.words.find("12.0 fps of 25"), std::string::npos) << v.words;

  in.frame_rate_hz = 25;
  in.dropped_recently = 3;
  EXPECT_EQ(classifyHealth(in).state, HealthState::kLate);
  in.dropped_recently = 0;
  in.last_error = "camera timeout";
  v = classifyHealth(in);
  EXPECT_EQ(v.state, HealthState::kLate);
  EXPECT_NE(v.words.find("camera timeout"), std::string::npos);
  in.last_error.clear();

  in.silent_ms = 600;
  EXPECT_EQ(classifyHealth(in).state, HealthState::kLate);
  in.silent_ms = 1500;
  v = classifyHealth(in);
  EXPECT_EQ(v.state, HealthState::kLost);
  EXPECT_NE(v.words.find("1.5 s"), std::string::npos) << v.words;
}

TEST(CameraHealth, AnExitedProcessIsLostAtOnce) {
  // A killed node: its last message was a moment ago, but its process is gone.
  HealthInput in;
  in.silent_ms = 10;
  in.frame_rate_hz = 25;
  in.process_exited = true;
  const HealthVerdict v = classifyHealth(in);
  EXPECT_EQ(v.state, HealthState::kLost);
  EXPECT_STREQ(healthStateName(v.state), "lost");
}

TEST(CameraHealth, ThresholdsAreTheCallers) {
  HealthThresholds t;
  t.late_after_ms = 50;
  t.lost_after_ms = 100;
  HealthInput in;
  in.silent_ms = 60;
  EXPECT_EQ(classifyHealth(in, t).state, HealthState::kLate);
  in.silent_ms = 100;
  EXPECT_EQ(classifyHealth(in, t).state, HealthState::kLost);
}

TEST(CameraHealth, HistoryKeepsTheLatestSamples) {
  HealthHistory h(3);
  for (int i = 0; i < 5; ++i) h.add("cam1", i, 10.0 * i);
  h.add("cam2", 0, 1);
  const auto& s = h.samples("cam1");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_DOUBLE_EQ(s.front().value, 20);
  EXPECT_DOUBLE_EQ(s.back().value, 40);
  EXPECT_TRUE(h.samples("nobody").empty());
  EXPECT_EQ(h.keys(), (std::vector<std::string>{"cam1", "cam2"}));
}

}  // namespace
}  // namespace lumistage
