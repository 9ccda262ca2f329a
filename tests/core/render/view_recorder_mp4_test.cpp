// The view recorder's MP4: H.264 through FFmpeg, read back through FFmpeg with every frame (skipped
// frame ids repeat the image before), a full disk said, a crash recovered.
#include <gtest/gtest.h>

#include <csignal>
#include <opencv2/videoio.hpp>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/render/video_file.h"
#include "core/render/view_recorder.h"
#include "tests/core/render/recorded_video.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using testing::errorOf;
using testing::testFolder;

using testing::solid;

// Every frame of the video, as the mean B, G, R of each.
std::vector<cv::Scalar> readBack(const std::filesystem::path& file, cv::Size* size) {
  return testing::readBack(file, size, cv::CAP_FFMPEG);
}

TEST(ViewRecorderMp4, WritesEveryFrameAtTheCamerasRateAsH264) {
  const std::filesystem::path file = testFolder("view_recorder_mp4") / "view.mp4";
  {
    ViewRecorder recorder(file, 30, 4);
    const auto red = solid(64, 48, 220, 20, 20), green = solid(64, 48, 20, 220, 20),
               blue = solid(64, 48, 20, 20, 220);
    EXPECT_TRUE(recorder.add(10, 64, 48, red));
    EXPECT_TRUE(recorder.add(11, 64, 48, green));
    EXPECT_TRUE(recorder.add(14, 64, 48, blue));  // 12 and 13 were skipped: green twice more
    EXPECT_FALSE(recorder.add(13, 64, 48, red));  // older than the last: left out
    EXPECT_TRUE(recorder.add(30, 32, 24, solid(32, 24, 220, 20, 20)));  // a gap of 15: not filled
    EXPECT_EQ(recorder.framesWritten(), 6);
    EXPECT_TRUE(recorder.close()) << recorder.status().error();
  }
  const VideoFileInfo info = probeVideoFile(file);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_EQ(info.fps, 30);
  EXPECT_EQ(info.frames, 6);
  cv::Size size;
  const std::vector<cv::Scalar> means = readBack(file, &size);
  ASSERT_EQ(means.size(), 6u);
  EXPECT_EQ(size, cv::Size(64, 48));           // the smaller image was scaled to the video's size
  const int expected[6] = {2, 1, 1, 1, 0, 2};  // the dominant channel, B G R order
  for (int i = 0; i < 6; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (c == expected[i]) {
        EXPECT_GT(means[i][c], 180) << "frame " << i;
      } else {
        EXPECT_LT(means[i][c], 60) << "frame " << i << " channel " << c;
      }
    }
  }
}

// The disk fills while recording (a file size limit, in a child process): FFmpeg's write fails,
// add() or close() says so naming the file, and the older video under the name is left as it was.
TEST(ViewRecorderMp4, AFullDiskLeavesTheOlderVideoAndSaysSo) {
  const std::filesystem::path dir = testFolder("view_recorder_mp4_full");
  const std::filesystem::path file = dir / "take.mp4";
  {
    ViewRecorder old(file, 30);
    for (int f = 0; f < 3; ++f) old.add(f, 64, 48, solid(64, 48, 220, 20, 20));
  }
  const std::string before = readFile(file);
  const int result = testing::inChildProcess([&] {
    testing::limitFileSize(100'000);
    ViewRecorder recorder(file, 30);
    std::vector<uint8_t> noise(size_t(320) * 240 * 4);
    uint32_t x = 1;
    try {
      for (int f = 0; f < 60; ++f) {
        for (uint8_t& v : noise) v = uint8_t((x = x * 1664525u + 1013904223u) >> 24);
        recorder.add(f, 320, 240, noise);
      }
    } catch (const Error& e) {
      const std::string error = e.what();
      return error.find(file.string() + ": the recording stops: ") == 0 &&
                     error.find("(disk full?) (File too large)") != std::string::npos
                 ? 0
                 : 4;
    }
    if (recorder.close()) return 2;
    return recorder.status().error().find(file.string()) == 0 ? 0 : 3;
  });
  EXPECT_EQ(result, 0) << "2: a torn video taken for whole, 3, 4: not said by name, 100: threw";
  EXPECT_EQ(readFile(file), before);
  EXPECT_TRUE(std::filesystem::exists(dir / "take.partial.mp4"));
}

// Killed while recording: the fragmented MP4 left behind is recovered into a plain MP4 of its
// whole seconds, and a new recording under the name goes beside it.
TEST(ViewRecorderMp4, ARecordingThatNeverClosedIsRecovered) {
  const std::filesystem::path dir = testFolder("view_recorder_mp4_crash");
  const std::filesystem::path file = dir / "take.mp4", partial = dir / "take.partial.mp4";
  constexpr int kFrames = 80;
  testing::inChildProcess([&] {
    ViewRecorder recorder(file, 25);
    for (int f = 0; f < kFrames; ++f) {
      recorder.add(f, 160, 120, solid(160, 120, uint8_t(3 * f), 100, 100));
    }
    std::raise(SIGKILL);
    return 0;
  });
  ASSERT_TRUE(std::filesystem::exists(partial));
  EXPECT_FALSE(std::filesystem::exists(file));
  const std::string left = readFile(partial);
  EXPECT_EQ(recoveredVideoPath(partial), dir / "take-recovered.mp4");
  const RecoveredVideo r = recoverPartialVideo(partial, recoveredVideoPath(partial));
  EXPECT_GE(r.frames, 50);  // a fragment a second, 25 frames; the encoder may hold the last few
  EXPECT_LE(r.frames, kFrames);
  EXPECT_EQ(r.frames % 25, 0);
  EXPECT_EQ(r.fps, 25);
  EXPECT_EQ(readFile(partial), left);
  const VideoFileInfo info = probeVideoFile(dir / "take-recovered.mp4");
  EXPECT_EQ(info.frames, r.frames);
  EXPECT_EQ(info.fps, 25);
  cv::Size size;
  const std::vector<cv::Scalar> means = readBack(dir / "take-recovered.mp4", &size);
  ASSERT_EQ(int64_t(means.size()), r.frames);
  for (size_t f = 0; f < means.size(); ++f) EXPECT_NEAR(means[f][2], 3.0 * double(f), 4) << f;
  EXPECT_NE(
      errorOf([&] { recoverPartialVideo(partial, dir / "take-recovered.mp4"); }).find("exists"),
      std::string::npos);
  {
    ViewRecorder again(file, 25);
    EXPECT_EQ(again.leftover(), partial);
    EXPECT_TRUE(again.add(0, 64, 48, solid(64, 48, 220, 20, 20)));
    EXPECT_TRUE(again.close()) << again.status().error();
  }
  EXPECT_EQ(probeVideoFile(file).frames, 1);
  EXPECT_EQ(readFile(partial), left);
}

}  // namespace
}  // namespace lumistage
