#include "core/pipeline/pipeline.h"

#include <gtest/gtest.h>
#include <poll.h>

#include <condition_variable>
#include <thread>

#include "core/pipeline/wakeup.h"

namespace lumistage {
namespace {

struct TestFrame {
  int64_t id = 0;
  std::vector<int> visited;
  FrameTrace trace;
};

TEST(BoundedQueue, DropsTheOldestWhenFullAndDrainsAfterClose) {
  BoundedQueue<int> queue(2);
  EXPECT_FALSE(queue.push(1));
  EXPECT_FALSE(queue.push(2));
  EXPECT_EQ(queue.push(3), 1);  // 1 pushed out: latency never grows
  EXPECT_EQ(queue.drops(), 1);
  EXPECT_EQ(queue.pop(std::chrono::milliseconds(10)), 2);
  queue.close();
  EXPECT_EQ(queue.push(4), 4);  // refused after close
  EXPECT_EQ(queue.pop(std::chrono::milliseconds(10)), 3);
  EXPECT_FALSE(queue.pop(std::chrono::milliseconds(10)));
}

TEST(Wakeup, APollOnItsDescriptorEndsWhenNotifiedAndNotAfterClear) {
  Wakeup wakeup;
  pollfd item{wakeup.fd(), POLLIN, 0};
  EXPECT_EQ(poll(&item, 1, 0), 0);
  std::thread other([&] { wakeup.notify(); });
  EXPECT_EQ(poll(&item, 1, 5000), 1);  // woken by the other thread, long before 5 s
  other.join();
  wakeup.notify();  // twice before one clear: one clear is enough
  wakeup.clear();
  EXPECT_EQ(poll(&item, 1, 0), 0);
  // Its own wait: ended by a notification from another thread, long before its 5 s.
  const auto start = std::chrono::steady_clock::now();
  std::thread again([&] { wakeup.notify(); });
  wakeup.wait(std::chrono::seconds(5));
  again.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(4));
}

// Four stages that each wait until all four are busy at once: it passes only if four frames are
// in flight simultaneously, each in its own stage.
TEST(RecentSamples, EventsPerSecondOverTheLatestOnly) {
  EXPECT_EQ(eventsPerSecond({}), 0);
  EXPECT_EQ(eventsPerSecond({5e9}), 0);
  EXPECT_EQ(eventsPerSecond({5e9, 5e9}), 0);
  // Ten a second for a while, then two a second: the ring of the latest 5 tells the rate now.
  RecentSamples times(5);
  double t = 0;
  for (int i = 0; i < 20; ++i) times.add(t += 0.1e9);
  EXPECT_DOUBLE_EQ(eventsPerSecond(times.values()), 10.0);
  for (int i = 0; i < 5; ++i) times.add(t += 0.5e9);
  EXPECT_DOUBLE_EQ(eventsPerSecond(times.values()), 2.0);
}

TEST(Pipeline, FourFramesInFlightInFourStages) {
  std::mutex mutex;
  std::condition_variable all_busy;
  int busy = 0, rounds_with_all_four = 0;
  auto stage = [&](int index) {
    return [&, index](TestFrame& f) {
      std::unique_lock lock(mutex);
      ++busy;
      if (busy == 4) {
        ++rounds_with_all_four;
        all_busy.notify_all();
      } else {
        all_busy.wait_for(lock, std::chrono::milliseconds(50), [&] { return busy >= 4; });
      }
      f.visited.push_back(index);
      lock.unlock();
      std::this_thread::yield();
      lock.lock();
      --busy;
      return true;
    };
  };
  Pipeline<TestFrame> pipeline;
  for (int s = 0; s < 4; ++s) pipeline.addStage("stage" + std::to_string(s), stage(s), 1);
  pipeline.start();
  std::vector<int64_t> out;
  for (int64_t id = 0; id < 40; ++id) {
    TestFrame f;
    f.id = id;
    pipeline.submit(std::move(f));
    if (auto done = pipeline.next(std::chrono::milliseconds(5))) {
      EXPECT_EQ(done->visited, (std::vector<int>{0, 1, 2, 3}));
      EXPECT_EQ(done->trace.stamps.size(), 4u);
      out.push_back(done->id);
    }
  }
  while (auto done = pipeline.next(std::chrono::milliseconds(500))) out.push_back(done->id);
  pipeline.stop();
  EXPECT_GT(rounds_with_all_four, 0);
  EXPECT_GE(pipeline.stats().max_in_flight, 4);
  ASSERT_FALSE(out.empty());
  for (size_t i = 1; i < out.size(); ++i) EXPECT_GT(out[i], out[i - 1]);  // in order
}

TEST(Pipeline, ASlowStageDropsOldFramesInsteadOfGrowingLatency) {
  std::atomic<bool> release{false};
  Pipeline<TestFrame> pipeline;
  pipeline.addStage(
      "capture", [](TestFrame&) { return true; }, 2);
  // The slow stage holds its first frame until released, as a stalled module would.
  pipeline.addStage(
      "slow",
      [&](TestFrame&) {
        while (!release) std::this_thread::yield();
        return true;
      },
      2);
  pipeline.addStage(
      "odd ones out", [](TestFrame& f) { return f.id % 2 == 0; }, 2);
  pipeline.start();
  for (int64_t id = 0; id < 50; ++id) {
    TestFrame f;
    f.id = id;
    pipeline.submit(std::move(f));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let capture push into "slow"
  release = true;
  std::vector<int64_t> out;
  while (auto done = pipeline.next(std::chrono::milliseconds(300))) out.push_back(done->id);
  pipeline.stop();
  const PipelineStats stats = pipeline.stats();
  // The queue before the slow stage held two frames: the rest were dropped, the newest kept.
  EXPECT_GT(stats.stages[1].dropped + stats.stages[0].dropped, 40);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back(), 48);  // the newest even frame made it: old ones were dropped, not queued
  for (int64_t id : out) EXPECT_EQ(id % 2, 0);
  EXPECT_GT(stats.stages[2].rejected, 0);
  EXPECT_EQ(stats.frames_out, static_cast<int64_t>(out.size()));
}

}  // namespace
}  // namespace lumistage
