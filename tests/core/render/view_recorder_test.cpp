// The view recorder writes a real Motion-JPEG AVI that OpenCV reads back: frames in real time
// (skipped frame ids repeat the image before), sizes kept, bad requests refused by name.
#include "core/render/view_recorder.h"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <opencv2/videoio.hpp>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/net/message_codec.h"
#include "tests/core/render/recorded_video.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using testing::errorOf;
using testing::testFolder;

using testing::solid;

// Every frame of the video, as the mean B, G, R of each.
std::vector<cv::Scalar> readBack(const std::filesystem::path& file, cv::Size* size) {
  return testing::readBack(file, size, cv::CAP_OPENCV_MJPEG);
}

TEST(ViewRecorder, WritesEveryFrameAtTheCamerasRate) {
  const std::filesystem::path file = testFolder("view_recorder") / "view.avi";
  {
    ViewRecorder recorder(file, 30, 4);
    const auto red = solid(64, 48, 220, 20, 20), green = solid(64, 48, 20, 220, 20),
               blue = solid(64, 48, 20, 20, 220);
    EXPECT_TRUE(recorder.add(10, 64, 48, red));
    EXPECT_TRUE(recorder.add(11, 64, 48, green));
    EXPECT_TRUE(recorder.add(14, 64, 48, blue));  // 12 and 13 were skipped: green twice more
    EXPECT_FALSE(recorder.add(13, 64, 48, red));  // older than the last: left out
    EXPECT_TRUE(recorder.add(30, 32, 24, solid(32, 24, 220, 20, 20)));  // a gap of 15: not filled
    // The cameras restarted, the studio followed their ids back from 1000 to 2: recorded from
    // there (it stopped until the ids passed 1000 again).
    EXPECT_TRUE(recorder.add(1000, 64, 48, blue));
    EXPECT_TRUE(recorder.add(2, 64, 48, green));
    static_assert(1000 - 2 > kFrameIdWindow);
    EXPECT_EQ(recorder.framesWritten(), 8);
    EXPECT_EQ(recorder.width(), 64);
  }
  cv::Size size;
  const std::vector<cv::Scalar> means = readBack(file, &size);
  ASSERT_EQ(means.size(), 8u);
  EXPECT_EQ(size, cv::Size(64, 48));  // the smaller image was scaled to the video's size
  const int expected[8] = {2, 1, 1, 1, 0, 2, 0, 1};  // the dominant channel, B G R order
  for (int i = 0; i < 8; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (c == expected[i]) {
        EXPECT_GT(means[i][c], 180) << "frame " << i;
      } else {
        EXPECT_LT(means[i][c], 60) << "frame " << i << " channel " << c;
      }
    }
  }
}

// The video is made beside its name and put in its place only once it reads back whole: an older
// video under the name stays until then, and is replaced by the whole new one.
TEST(ViewRecorder, ReplacesAnOlderVideoOnlyWhenWhole) {
  const std::filesystem::path dir = testFolder("view_recorder_replace");
  const std::filesystem::path file = dir / "take.avi";
  std::filesystem::remove(file);
  const auto red = solid(64, 48, 220, 20, 20);
  {
    ViewRecorder old(file, 30);
    for (int f = 0; f < 3; ++f) old.add(f, 64, 48, red);
  }
  ViewRecorder recorder(file, 30);
  for (int f = 0; f < 5; ++f) recorder.add(f, 64, 48, red);
  EXPECT_TRUE(std::filesystem::exists(dir / "take.partial.avi"));
  cv::Size size;
  EXPECT_EQ(readBack(file, &size).size(), 3u);  // the older video, untouched while recording
  EXPECT_TRUE(recorder.close());
  EXPECT_EQ(recorder.status().error(), "");
  EXPECT_EQ(readBack(file, &size).size(), 5u);
  EXPECT_FALSE(std::filesystem::exists(dir / "take.partial.avi"));
}

// The disk fills while recording (a file size limit, in a child process): OpenCV's writer drops
// its write errors, the video reads back short, and close() says so; the older video under the
// name is left as it was and what was written is kept beside it.
TEST(ViewRecorder, AFullDiskLeavesTheOlderVideoAndSaysSo) {
  const std::filesystem::path dir = testFolder("view_recorder_full");
  const std::filesystem::path file = dir / "take.avi";
  std::filesystem::remove(file);
  {
    ViewRecorder old(file, 30);
    for (int f = 0; f < 3; ++f) old.add(f, 64, 48, solid(64, 48, 220, 20, 20));
  }
  const std::string before = readFile(file);
  const int result = testing::inChildProcess([&] {
    testing::limitFileSize(200'000);
    ViewRecorder recorder(file, 30);
    std::vector<uint8_t> noise(size_t(640) * 480 * 4);
    uint32_t x = 1;
    for (int f = 0; f < 60; ++f) {
      for (uint8_t& v : noise) v = uint8_t((x = x * 1664525u + 1013904223u) >> 24);
      recorder.add(f, 640, 480, noise);
    }
    if (recorder.close()) return 2;
    return recorder.status().error().find("the video reads back") == std::string::npos ? 3 : 0;
  });
  EXPECT_EQ(result, 0) << "2: a torn video taken for whole, 3: not said, 100: threw";
  EXPECT_EQ(readFile(file), before);
  EXPECT_TRUE(std::filesystem::exists(dir / "take.partial.avi"));
}

TEST(ViewRecorder, RefusesWhatItCannotWriteByName) {
  const std::filesystem::path dir = testFolder("view_recorder");
  EXPECT_NE(errorOf([&] {
              ViewRecorder(dir / "view.mkv", 30);
            }).find("view.mkv: the view is recorded as H.264 in an MP4 or Motion-JPEG in an AVI"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { ViewRecorder(dir / "missing" / "view.avi", 30); }).find("no folder"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { ViewRecorder(dir / "view.avi", 0); }).find("0 to 1000"),
            std::string::npos);
  // Nothing is written before the first frame, and an empty recording leaves no file.
  { ViewRecorder recorder(dir / "empty.avi", 30); }
  EXPECT_FALSE(std::filesystem::exists(dir / "empty.avi"));
}

// The studio is killed while recording (SIGKILL: no destructor, no flush): the partial video has
// no index and no counts. recoverPartialVideo makes a whole video of its whole frames, in order,
// leaving the partial file as it was; a new recording under the name never writes over it.
TEST(ViewRecorder, ARecordingThatNeverClosedIsRecoveredAndNeverWrittenOver) {
  const std::filesystem::path dir = testFolder("view_recorder_crash");
  const std::filesystem::path file = dir / "take.avi", partial = dir / "take.partial.avi";
  constexpr int kFrames = 40;
  testing::inChildProcess([&] {
    ViewRecorder recorder(file, 25);
    // The upper half grey level 5 i (frame i), the lower half noise (large frames: past the
    // writer's buffer, most of them reach the disk before the kill).
    std::vector<uint8_t> rgba(size_t(320) * 240 * 4, 255);
    uint32_t x = 7;
    for (int f = 0; f < kFrames; ++f) {
      for (size_t p = 0; p < rgba.size(); p += 4) {
        for (int c = 0; c < 3; ++c) {
          rgba[p + c] = p < rgba.size() / 2 ? uint8_t(5 * f)
                                            : uint8_t((x = x * 1664525u + 1013904223u) >> 24);
        }
      }
      recorder.add(f, 320, 240, rgba);
    }
    std::raise(SIGKILL);
    return 0;
  });
  ASSERT_TRUE(std::filesystem::exists(partial));
  EXPECT_FALSE(std::filesystem::exists(file));
  const std::string left = readFile(partial);
  {
    cv::VideoCapture torn(partial.string(), cv::CAP_OPENCV_MJPEG);  // what a crash leaves
    EXPECT_FALSE(torn.isOpened() && torn.get(cv::CAP_PROP_FRAME_COUNT) > 0);
  }

  const std::filesystem::path recovered = dir / "recovered.avi";
  const RecoveredVideo r = recoverPartialVideo(partial, recovered);
  EXPECT_GE(r.frames, kFrames / 2);
  EXPECT_LE(r.frames, kFrames);
  EXPECT_EQ(r.fps, 25);
  EXPECT_EQ(readFile(partial), left);
  cv::VideoCapture video(recovered.string(), cv::CAP_OPENCV_MJPEG);
  ASSERT_TRUE(video.isOpened());
  EXPECT_EQ(int64_t(video.get(cv::CAP_PROP_FRAME_COUNT)), r.frames);
  EXPECT_EQ(video.get(cv::CAP_PROP_FPS), 25);
  cv::Mat frame;
  int64_t read = 0;
  while (video.read(frame)) {
    ASSERT_EQ(frame.size(), cv::Size(320, 240));
    EXPECT_NEAR(cv::mean(frame(cv::Rect(0, 0, 320, 110)))[1], 5.0 * double(read), 3) << read;
    ++read;
  }
  EXPECT_EQ(read, r.frames);
  EXPECT_NE(errorOf([&] { recoverPartialVideo(partial, recovered); }).find("exists"),
            std::string::npos);
  // Where the studio and `lumistage video recover` put it by default: NAME-recovered.avi, then
  // -2...; and whether it was made since the partial file last changed.
  EXPECT_EQ(recoveredVideoPath(partial), dir / "take-recovered.avi");
  EXPECT_EQ(recoveredVideoPath(dir / "take.partial-3.avi"), dir / "take-recovered.avi");
  EXPECT_FALSE(wasRecovered(partial));
  EXPECT_EQ(recoverPartialVideo(partial, recoveredVideoPath(partial)).frames, r.frames);
  EXPECT_TRUE(wasRecovered(partial));
  EXPECT_EQ(recoveredVideoPath(partial), dir / "take-recovered-2.avi");
  std::filesystem::last_write_time(
      partial,
      std::filesystem::last_write_time(dir / "take-recovered.avi") + std::chrono::hours(1));
  EXPECT_FALSE(wasRecovered(partial));  // changed since
  EXPECT_FALSE(wasRecovered(dir / "none.partial.avi"));

  // Recording again under the name: beside the left partial file, which stays as it was.
  {
    ViewRecorder again(file, 25);
    EXPECT_EQ(again.leftover(), partial);
    EXPECT_TRUE(again.add(0, 64, 48, solid(64, 48, 220, 20, 20)));
    EXPECT_TRUE(std::filesystem::exists(dir / "take.partial-2.avi"));
    EXPECT_TRUE(again.close()) << again.status().error();
  }
  cv::Size size;
  EXPECT_EQ(readBack(file, &size).size(), 1u);
  EXPECT_EQ(readFile(partial), left);
  // What is not such a recording says so.
  writeFileAtomically(dir / "not.partial.avi", "RIFF....WAVEfmt ");
  EXPECT_NE(errorOf([&] {
              recoverPartialVideo(dir / "not.partial.avi", dir / "x.avi");
            }).find("not.partial.avi: not an AVI file"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { recoverPartialVideo(recovered, dir / "y.avi"); }).find("it was closed"),
            std::string::npos);
}

}  // namespace
}  // namespace lumistage
