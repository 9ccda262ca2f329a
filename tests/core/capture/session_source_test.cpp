#include "core/capture/session_source.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "core/base/error.h"
#include "core/capture/session_recorder.h"
#include "tests/core/capture/capture_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

ReplayOptions replay(ReplayMode mode, bool loop = false, size_t memory_limit = size_t(1) << 30,
                     std::vector<int> cameras = {}) {
  ReplayOptions options;
  options.mode = mode;
  options.loop = loop;
  options.memory_limit_bytes = memory_limit;
  options.cameras = std::move(cameras);
  return options;
}

using namespace lumistage::test;
using std::chrono::milliseconds;

constexpr int64_t kPeriodNs = 10'000'000;  // 100 fps: a recorded-rate replay takes 50 ms

// Records `count` sets through SessionRecorder, 10 ms apart.
void record(const fs::path& folder, const Rig& rig, PixelFormat format, int count) {
  SessionRecorder recorder(folder, rig, format, 100.0, "test", count);
  for (int f = 0; f < count; ++f)
    ASSERT_TRUE(recorder.push(f, f * kPeriodNs, frameImages(rig, format, f)));
  recorder.stop();
  ASSERT_EQ(recorder.stats().written, count);
}

TEST(Replay, EveryModeGivesBackExactlyWhatWasRecorded) {
  const Rig rig = smallRig();
  constexpr int kFrames = 6;
  for (PixelFormat format : {PixelFormat::kBayerRggb8, PixelFormat::kRgb8}) {
    const fs::path folder = freshFolder(std::string("replay_") + pixelFormatName(format));
    record(folder, rig, format, kFrames);
    for (ReplayMode mode :
         {ReplayMode::kRecordedRate, ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
      SCOPED_TRACE(int(mode));
      SessionSource source(folder, replay(mode));
      EXPECT_TRUE(source.rig() == rig);
      const auto start = std::chrono::steady_clock::now();
      CameraFrame frame;
      int got = 0;
      while (!source.finished()) {
        if (!source.next(frame, milliseconds(5))) continue;  // recorded rate: not due yet
        const int set = got / 3, camera = got % 3;
        ASSERT_EQ(frame.camera, camera);  // camera by camera, in rig order
        EXPECT_EQ(frame.frame_id, set);
        EXPECT_EQ(frame.timestamp_ns, set * kPeriodNs);
        EXPECT_TRUE(frame.image.pixels == frameImages(rig, format, set)[camera].pixels);
        ++got;
      }
      EXPECT_EQ(got, kFrames * 3);
      EXPECT_FALSE(source.next(frame, milliseconds(0)));
      EXPECT_EQ(source.stats(0).frames, kFrames);
      EXPECT_TRUE(source.stats(0).last_error.empty());
      if (mode == ReplayMode::kRecordedRate) {
        EXPECT_GE(std::chrono::steady_clock::now() - start, milliseconds(50));
      }
    }
    fs::remove_all(folder);
  }
}

TEST(Replay, LoopsWithIdsAndTimestampsGoingOn) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_loop");
  record(folder, rig, PixelFormat::kMono8, 2);
  SessionSource source(folder, replay(ReplayMode::kFromMemory, true));
  CameraFrame frame;
  for (int i = 0; i < 5 * 3; ++i) {
    ASSERT_TRUE(source.next(frame, milliseconds(0)));
    const int set = i / 3;
    EXPECT_EQ(frame.frame_id, set);
    EXPECT_EQ(frame.timestamp_ns, set * kPeriodNs);  // the span is last - first + one period
    EXPECT_TRUE(frame.image.pixels ==
                frameImages(rig, PixelFormat::kMono8, set % 2)[frame.camera].pixels);
  }
  EXPECT_FALSE(source.finished());
  fs::remove_all(folder);
}

// The studio's previews want a few images only: a frame taken without its image leaves the
// caller's buffer as it was, and moves on exactly as a whole one (camera, id, time, counts).
TEST(Replay, FramesTakenWithoutTheirImagesMoveOnAsWholeOnes) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_without_images");
  constexpr int kFrames = 4;
  record(folder, rig, PixelFormat::kRgb8, kFrames);
  for (ReplayMode mode : {ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
    SCOPED_TRACE(int(mode));
    SessionSource source(folder, replay(mode));
    CameraFrame frame;
    const Image untouched = frameImages(rig, PixelFormat::kMono8, 7)[0];
    for (int i = 0; i < kFrames * 3; ++i) {
      const int set = i / 3, camera = i % 3;
      ASSERT_EQ(source.nextCamera(), camera);
      const bool with_image = i % 2 == 1;  // every other frame, so each camera has both kinds
      if (!with_image) frame.image = untouched;
      ASSERT_TRUE(source.next(frame, milliseconds(0), with_image));
      EXPECT_EQ(frame.camera, camera);
      EXPECT_EQ(frame.frame_id, set);
      EXPECT_EQ(frame.timestamp_ns, set * kPeriodNs);
      EXPECT_TRUE(
          frame.image.pixels ==
          (with_image ? frameImages(rig, PixelFormat::kRgb8, set)[camera] : untouched).pixels);
    }
    EXPECT_TRUE(source.finished());
    for (int c = 0; c < 3; ++c) EXPECT_EQ(source.stats(c).frames, kFrames);
  }
  fs::remove_all(folder);
}

TEST(Replay, FromMemoryOverTheLimitSaysHowMuchItWouldNeed) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_limit");
  record(folder, rig, PixelFormat::kRgb8, 2);
  try {
    SessionSource source(folder, replay(ReplayMode::kFromMemory, false, 10000));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("replaying from memory needs 0.1 MiB (2 frames of 3 "
                                         "cameras), over the limit of 0.0 MiB"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(folder);
}

// Loading a session into memory stops when asked (the studio's window closed meanwhile).
TEST(Replay, FromMemoryLoadingStopsWhenCancelled) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_cancel");
  record(folder, rig, PixelFormat::kRgb8, 2);
  std::atomic<bool> cancel{true};
  ReplayOptions options = replay(ReplayMode::kFromMemory, false);
  options.cancel = &cancel;
  EXPECT_THROW(SessionSource(folder, options), Error);
  cancel = false;
  SessionSource loaded(folder, options);
  EXPECT_FALSE(loaded.finished());
  fs::remove_all(folder);
}

// A PNG whose signature, header and end chunk are right (the check at opening passes) but whose
// image data is garbage.
void garbleImageData(const fs::path& png) {
  std::string bytes = readFile(png);
  ASSERT_GT(bytes.size(), 60u);
  // Past the signature, IHDR and the first chunk's length and type; short of the end chunk.
  for (size_t i = 41; i + 20 < bytes.size(); ++i) bytes[i] = char(0x55);
  std::ofstream(png, std::ios::binary | std::ios::trunc) << bytes;
}

// Every frame a source serves until it finishes (or `limit`), with what was asked of next().
int drain(SessionSource& source, int limit = 1000) {
  CameraFrame frame;
  int got = 0;
  for (int calls = 0; !source.finished() && calls < limit; ++calls)
    got += source.next(frame, milliseconds(0));
  return got;
}

TEST(Replay, AnImageDamagedAfterOpeningIsSkippedCountedAndSaid) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_damaged");
  record(folder, rig, PixelFormat::kMono8, 3);
  SessionSource source(folder, replay(ReplayMode::kAsFastAsPossible));
  std::ofstream(folder / "cam02" / "000001.png", std::ios::trunc) << "not a png";
  // Set 1 is skipped; sets 0 and 2 come out whole.
  EXPECT_EQ(drain(source), 6);
  EXPECT_TRUE(source.finished());
  EXPECT_EQ(source.failure(), "");
  for (int c = 0; c < 3; ++c) EXPECT_EQ(source.stats(c).dropped, 1) << c;
  EXPECT_NE(source.stats(1).last_error.find("cam02/000001.png"), std::string::npos)
      << source.stats(1).last_error;
  fs::remove_all(folder);
}

TEST(Replay, GarbageImageDataPassesTheOpeningCheckAndIsSkippedInEveryMode) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_garbage");
  record(folder, rig, PixelFormat::kMono8, 4);
  garbleImageData(folder / "cam01" / "000002.png");
  for (ReplayMode mode : {ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
    SessionSource source(folder, replay(mode));
    ASSERT_EQ(source.reader().frameCount(), 4);  // the header and end chunk are right
    EXPECT_EQ(drain(source), 9);
    EXPECT_EQ(source.failure(), "");
    EXPECT_EQ(source.stats(0).dropped, 1);
    EXPECT_NE(source.stats(0).last_error.find("cam01/000002.png"), std::string::npos)
        << source.stats(0).last_error;
  }
  // Looping and synchronised, as a node replays: it goes on past the damaged set, loop after loop.
  ReplayOptions options = replay(ReplayMode::kRecordedRate, true, size_t(1) << 30, {0, 1});
  options.synchronized = true;
  SessionSource node(folder, options);
  CameraFrame frame;
  int got = 0;
  for (int calls = 0; calls < 4000 && got < 2 * 10; ++calls)
    got += node.next(frame, milliseconds(5));
  EXPECT_EQ(got, 20);
  EXPECT_FALSE(node.finished());
  fs::remove_all(folder);
}

TEST(Replay, WhenEveryFrameFailsTheReplayFinishesAndSaysWhy) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("replay_all_damaged");
  record(folder, rig, PixelFormat::kMono8, 2);
  SessionSource source(folder, replay(ReplayMode::kAsFastAsPossible, true));
  for (const char* file : {"000000.png", "000001.png"}) garbleImageData(folder / "cam01" / file);
  EXPECT_EQ(drain(source), 0);
  EXPECT_TRUE(source.finished());
  EXPECT_NE(source.failure().find("none of the session's 2 frames left can be decoded"),
            std::string::npos)
      << source.failure();
  // From memory: refused when opened, naming the first file.
  const std::string m = testing::errorOf([&] {
    const SessionSource opened(folder, replay(ReplayMode::kFromMemory));
    ADD_FAILURE() << "opened, with " << opened.reader().frameCount() << " frames";
  });
  EXPECT_NE(m.find("no frame of the session can be decoded"), std::string::npos) << m;
  EXPECT_NE(m.find("cam01/000000.png"), std::string::npos) << m;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

TEST(Replay, ANodeReplaysOnlyItsOwnCameras) {
  const fs::path folder = freshFolder("replay_subset");
  const Rig rig = smallRig();
  writeSession(folder, rig, PixelFormat::kBayerRggb8, 4);
  for (ReplayMode mode : {ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
    SessionSource source(folder, replay(mode, false, size_t(1) << 30, {2, 0}));
    CameraFrame frame;
    std::vector<int> served;
    while (source.next(frame, std::chrono::milliseconds(100))) {
      served.push_back(frame.camera);
      const std::vector<Image> expected =
          frameImages(rig, PixelFormat::kBayerRggb8, frame.frame_id);
      EXPECT_EQ(frame.image.pixels, expected[frame.camera].pixels);
    }
    EXPECT_EQ(served, (std::vector<int>{2, 0, 2, 0, 2, 0, 2, 0}));
    EXPECT_EQ(source.stats(1).frames, 0);
  }
  EXPECT_THROW(
      SessionSource(folder, replay(ReplayMode::kAsFastAsPossible, false, size_t(1) << 30, {7})),
      Error);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

TEST(Replay, SynchronizedReplaysShowTheSameFrameAtTheSameInstant) {
  // Two replays of one session (two nodes) started apart serve the same ids at the same ticks.
  const fs::path folder = freshFolder("replay_sync");
  const Rig rig = smallRig();
  writeSession(folder, rig, PixelFormat::kMono8, 5);
  ReplayOptions options = replay(ReplayMode::kFromMemory, false, size_t(1) << 30, {0});
  options.synchronized = true;
  SessionSource a(folder, options);
  std::this_thread::sleep_for(std::chrono::milliseconds(45));
  options.cameras = {1};
  SessionSource b(folder, options);
  CameraFrame fa, fb;
  for (int i = 0; i < 6; ++i) {
    ASSERT_TRUE(a.next(fa, std::chrono::milliseconds(200)));
    ASSERT_TRUE(b.next(fb, std::chrono::milliseconds(200)));
    // Whichever is behind (the test reads them one after the other) catches up.
    for (int step = 0; step < 20 && fa.frame_id != fb.frame_id; ++step) {
      if (fa.frame_id < fb.frame_id) {
        ASSERT_TRUE(a.next(fa, std::chrono::milliseconds(200)));
      } else {
        ASSERT_TRUE(b.next(fb, std::chrono::milliseconds(200)));
      }
    }
    EXPECT_EQ(fa.frame_id, fb.frame_id);
    EXPECT_EQ(fa.timestamp_ns, fb.timestamp_ns);
    // The content is the recorded frame of that tick, looping over the session.
    const int64_t recorded = fa.frame_id % 5;
    EXPECT_EQ(fa.image.pixels, frameImages(rig, PixelFormat::kMono8, recorded)[0].pixels);
    EXPECT_EQ(fb.image.pixels, frameImages(rig, PixelFormat::kMono8, recorded)[1].pixels);
  }
  EXPECT_FALSE(a.finished());
  fs::remove_all(folder);
}

TEST(Replay, ASynchronizedReplayCountsTheTicksItsReaderMissedAsDropped) {
  // A reader too slow for the cameras' rate misses their frames, as with real cameras, and the
  // cameras' health says so: every tick that passed unserved is a frame dropped.
  const fs::path folder = freshFolder("replay_sync_dropped");
  const Rig rig = smallRig();
  writeSession(folder, rig, PixelFormat::kMono8, 5);
  ReplayOptions options = replay(ReplayMode::kFromMemory, false, size_t(1) << 30, {0, 2});
  options.synchronized = true;
  SessionSource source(folder, options);
  CameraFrame frame;
  ASSERT_TRUE(source.next(frame, std::chrono::milliseconds(200)));
  ASSERT_TRUE(source.next(frame, std::chrono::milliseconds(200)));  // the set's second camera
  const int64_t first = frame.frame_id;
  for (int c : {0, 1, 2}) EXPECT_EQ(source.stats(c).dropped, 0) << c;
  const double period_s = 1.0 / source.reader().fps();
  std::this_thread::sleep_for(std::chrono::duration<double>(4.5 * period_s));
  ASSERT_TRUE(source.next(frame, std::chrono::milliseconds(200)));
  const int64_t missed = frame.frame_id - first - 1;
  EXPECT_GE(missed, 3);
  EXPECT_EQ(source.stats(0).dropped, missed);
  EXPECT_EQ(source.stats(2).dropped, missed);
  EXPECT_EQ(source.stats(1).dropped, 0);  // not replayed here
  fs::remove_all(folder);
}

// Frame f's mask of camera c (another tool's): a band of columns that moves with f and c.
std::vector<uint8_t> bandMask(const Camera& camera, int f, int c) {
  std::vector<uint8_t> mask(size_t(camera.width()) * camera.height(), 0);
  for (int y = 0; y < camera.height(); ++y)
    for (int x = 8 + f + 3 * c; x < 24 + f + 3 * c; ++x) mask[size_t(y) * camera.width() + x] = 255;
  return mask;
}

// A session of `count` frames with masks/ (what lumistage session import --masks writes).
void writeMasks(const fs::path& folder, const Rig& rig, int count) {
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    fs::create_directories(folder / "masks" / camera.name());
    for (int f = 0; f < count; ++f) {
      std::vector<uint8_t> mask = bandMask(camera, f, c);
      const cv::Mat image(camera.height(), camera.width(), CV_8UC1, mask.data());
      ASSERT_TRUE(cv::imwrite(
          (folder / "masks" / camera.name() / fmt::format("{:06}.png", f)).string(), image));
    }
  }
}

TEST(Replay, EveryModeDeliversEachFramesMaskWithIt) {
  const Rig rig = smallRig();
  constexpr int kFrames = 4;
  const fs::path folder = freshFolder("replay_masks");
  writeSession(folder, rig, PixelFormat::kRgb8, kFrames);
  {
    SessionSource without(folder, replay(ReplayMode::kAsFastAsPossible));
    EXPECT_FALSE(without.hasMasks(0));
    CameraFrame frame;
    ASSERT_TRUE(without.next(frame, milliseconds(5)));
    EXPECT_TRUE(frame.mask.empty());
  }
  writeMasks(folder, rig, kFrames);
  for (ReplayMode mode :
       {ReplayMode::kRecordedRate, ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
    SCOPED_TRACE(int(mode));
    SessionSource source(folder, replay(mode));
    EXPECT_TRUE(source.hasMasks(2));
    CameraFrame frame;
    int got = 0;
    while (!source.finished()) {
      if (!source.next(frame, milliseconds(5))) continue;
      const int set = got / 3;
      EXPECT_EQ(frame.frame_id, set);
      EXPECT_TRUE(frame.mask == bandMask(rig.camera(frame.camera), set, frame.camera))
          << "camera " << frame.camera << ", frame " << set;
      ++got;
    }
    EXPECT_EQ(got, kFrames * 3);
  }
  // Asked for the images alone: none.
  ReplayOptions images_only = replay(ReplayMode::kAsFastAsPossible);
  images_only.masks = false;
  SessionSource source(folder, images_only);
  EXPECT_FALSE(source.hasMasks(0));
  fs::remove_all(folder);
}

TEST(Replay, AFrameWhoseMaskCannotBeReadIsSkippedForItsCameraAlone) {
  const Rig rig = smallRig();
  constexpr int kFrames = 3;
  const fs::path folder = freshFolder("replay_bad_mask");
  writeSession(folder, rig, PixelFormat::kRgb8, kFrames);
  writeMasks(folder, rig, kFrames);
  const fs::path bad = folder / "masks" / rig.camera(1).name() / "000001.png";
  truncateFile(bad, 20);
  for (ReplayMode mode : {ReplayMode::kAsFastAsPossible, ReplayMode::kFromMemory}) {
    SCOPED_TRACE(int(mode));
    SessionSource source(folder, replay(mode));
    CameraFrame frame;
    std::vector<std::pair<int64_t, int>> delivered;
    while (!source.finished()) {
      if (source.next(frame, milliseconds(5))) delivered.push_back({frame.frame_id, frame.camera});
    }
    // Every frame but camera 1's of frame 1.
    ASSERT_EQ(delivered.size(), size_t(kFrames * 3 - 1));
    EXPECT_EQ(std::count(delivered.begin(), delivered.end(), std::pair<int64_t, int>(1, 1)), 0);
    EXPECT_EQ(std::count(delivered.begin(), delivered.end(), std::pair<int64_t, int>(1, 2)), 1);
    EXPECT_EQ(source.stats(1).dropped, 1);
    EXPECT_EQ(source.stats(0).dropped, 0);
    EXPECT_NE(source.stats(1).last_error.find(bad.string()), std::string::npos)
        << source.stats(1).last_error;
  }
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
