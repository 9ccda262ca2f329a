#include "core/capture/frame_grouper.h"

#include <gtest/gtest.h>

namespace lumistage {
namespace {

// A frame whose one pixel says which camera and id it is, to check what lands where.
CameraFrame makeFrame(int camera, int64_t id, int64_t timestamp_ns) {
  CameraFrame frame;
  frame.camera = camera;
  frame.frame_id = id;
  frame.timestamp_ns = timestamp_ns;
  frame.image.resize(PixelFormat::kMono8, 1, 1);
  frame.image.pixels[0] = uint8_t(id * 3 + camera);
  return frame;
}

bool push(FrameGrouper& grouper, int camera, int64_t id, int64_t timestamp_ns) {
  CameraFrame frame = makeFrame(camera, id, timestamp_ns);
  return grouper.push(frame);
}

TEST(FrameGrouper, GroupsInterleavedFramesAndReportsMissingAndLateCameras) {
  FrameGrouper grouper(3);
  std::vector<FrameSet> sets;
  FrameSet set;
  auto drain = [&] {
    while (grouper.pop(set)) sets.push_back(set);
  };
  // Camera 1 runs one frame behind; camera 2 loses frame 4.
  for (int64_t id = 0; id < 10; ++id) {
    push(grouper, 0, id, id * 1000);
    if (id != 4) push(grouper, 2, id, id * 1000);
    if (id > 0) push(grouper, 1, id - 1, (id - 1) * 1000);
    drain();
    if (id == 6) {
      EXPECT_EQ(grouper.lateCameras(), std::vector<int>{2});  // set 4 went out, with 5
    }
  }
  push(grouper, 1, 9, 9000);
  drain();
  ASSERT_EQ(sets.size(), 10u);
  for (int64_t id = 0; id < 10; ++id) {
    const FrameSet& s = sets[id];
    EXPECT_EQ(s.frame_id, id);
    EXPECT_EQ(s.complete(), id != 4) << id;
    for (int c = 0; c < 3; ++c) {
      if (!s.present[c]) continue;
      EXPECT_EQ(s.frames[c].camera, c);
      EXPECT_EQ(s.frames[c].image.pixels[0], uint8_t(id * 3 + c));
    }
  }
  EXPECT_EQ(sets[4].missing, std::vector<int>{2});
  EXPECT_FALSE(sets[4].present[2]);
  EXPECT_EQ(grouper.stats().complete, 9);
  EXPECT_EQ(grouper.stats().incomplete, 1);
  EXPECT_EQ(grouper.stats().missed, (std::vector<int64_t>{0, 0, 1}));
  EXPECT_TRUE(grouper.lateCameras().empty());
  EXPECT_EQ(grouper.pendingCount(), 0);
}

// Cameras without a common clock (GigE cameras' ticks since each one's power-up): a set's time is
// always the first camera's, whichever camera's frame came first, so that a recording's index
// follows one clock instead of jumping between them.
TEST(FrameGrouper, ASetsTimeIsOneCamerasClockWhateverArrivesFirst) {
  FrameGrouper grouper(2);
  FrameSet set;
  std::vector<int64_t> times;
  for (int64_t id = 0; id < 4; ++id) {
    const int64_t cam0 = 100'000'000'000 + id * 33'333'333,
                  cam1 = 5'000'000'000'000 + id * 33'333'333;
    if (id % 2) {
      push(grouper, 1, id, cam1);
      push(grouper, 0, id, cam0);
    } else {
      push(grouper, 0, id, cam0);
      push(grouper, 1, id, cam1);
    }
    while (grouper.pop(set)) times.push_back(set.timestamp_ns);
  }
  ASSERT_EQ(times.size(), 4u);
  for (int64_t id = 0; id < 4; ++id) EXPECT_EQ(times[id], 100'000'000'000 + id * 33'333'333);
  // Camera 0 missing from a set: camera 1's clock, the first present.
  FrameGrouper alone(2, {.max_pending = 1});
  push(alone, 1, 0, 7);
  push(alone, 1, 1, 8);
  ASSERT_TRUE(alone.pop(set));
  EXPECT_EQ(set.timestamp_ns, 7);
}

TEST(FrameGrouper, ACameraFarBehindIsNotWaitedOnAndMemoryStaysBounded) {
  FrameGrouperOptions options;
  options.max_pending = 3;
  options.max_ready = 4;
  FrameGrouper grouper(3, options);
  // Camera 2 stops after frame 1; nobody pops for a while.
  for (int64_t id = 0; id < 50; ++id) {
    push(grouper, 0, id, 0);
    push(grouper, 1, id, 0);
    if (id < 2) push(grouper, 2, id, 0);
    EXPECT_LE(grouper.pendingCount(), 3);
    EXPECT_LE(grouper.readyCount(), 4);
  }
  EXPECT_EQ(grouper.lateCameras(), std::vector<int>{2});
  EXPECT_GT(grouper.stats().evicted, 0);
  // Its frame 10 comes far too late: discarded and counted, never waited for.
  EXPECT_FALSE(push(grouper, 2, 10, 0));
  EXPECT_EQ(grouper.stats().stale, 1);
  FrameSet set;
  int64_t previous = -1;
  int popped = 0;
  while (grouper.pop(set)) {
    EXPECT_GT(set.frame_id, previous);  // in order, even after evictions
    EXPECT_EQ(set.missing, std::vector<int>{2});
    previous = set.frame_id;
    ++popped;
  }
  EXPECT_EQ(popped, 4);
  grouper.flush();
  while (grouper.pop(set)) ++popped;
  EXPECT_EQ(popped, 4 + 3);
  const FrameGrouperStats& stats = grouper.stats();
  EXPECT_EQ(stats.complete + stats.incomplete, 50);
  EXPECT_EQ(stats.complete, 2);
  EXPECT_EQ(stats.evicted, 50 - popped);
}

TEST(FrameGrouper, GroupsByTimestampWhenIdsAreNotComparable) {
  FrameGrouperOptions options;
  options.key = FrameGrouperOptions::Key::kTimestamp;
  options.tolerance_ns = 2'000'000;
  FrameGrouper grouper(3, options);
  const int64_t offsets[3] = {0, 1000, 77};  // every camera counts its own frames
  const int64_t jitter[3] = {0, 900'000, -700'000};
  FrameSet set;
  std::vector<FrameSet> sets;
  for (int64_t k = 0; k < 6; ++k) {
    for (int c : {2, 0, 1}) {
      if (c == 1 && k == 3) continue;  // camera 1 loses instant 3
      push(grouper, c, offsets[c] + k, k * 33'333'333 + jitter[c]);
    }
    while (grouper.pop(set)) sets.push_back(set);
  }
  grouper.flush();
  while (grouper.pop(set)) sets.push_back(set);
  ASSERT_EQ(sets.size(), 6u);
  for (int64_t k = 0; k < 6; ++k) {
    EXPECT_EQ(sets[k].complete(), k != 3) << k;
    for (int c = 0; c < 3; ++c) {
      if (sets[k].present[c]) {
        EXPECT_EQ(sets[k].frames[c].frame_id, offsets[c] + k);
      }
    }
  }
  EXPECT_EQ(sets[3].missing, std::vector<int>{1});
  // A frame 1 ms after an emitted set's is late for it, not the start of a new one.
  EXPECT_FALSE(push(grouper, 1, 2000, 5 * 33'333'333 + 1'000'000));
}

TEST(FrameGrouper, BuffersCirculateOnceWarmedUp) {
  FrameGrouper grouper(2);
  FrameSet set;
  CameraFrame frame;
  std::vector<const uint8_t*> buffers;
  for (int64_t id = 0; id < 20; ++id) {
    for (int c = 0; c < 2; ++c) {
      if (frame.image.pixels.empty()) frame.image.resize(PixelFormat::kMono8, 64, 48);
      frame.camera = c;
      frame.frame_id = id;
      const uint8_t* data = frame.image.pixels.data();
      if (id >= 10) {
        EXPECT_NE(std::find(buffers.begin(), buffers.end(), data), buffers.end());
      }
      if (id < 10 && std::find(buffers.begin(), buffers.end(), data) == buffers.end())
        buffers.push_back(data);
      ASSERT_TRUE(grouper.push(frame));
    }
    ASSERT_TRUE(grouper.pop(set));
    ASSERT_TRUE(set.complete());
  }
}

}  // namespace
}  // namespace lumistage
