// Video files through FFmpeg: what is written reads back through FFmpeg (libavformat's packets and
// OpenCV's FFmpeg reader) with every frame, its size and rate, and the picture that was written.
#include "core/render/video_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "core/base/error.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using testing::errorOf;
using testing::testFolder;

constexpr int kSquare = 24;

// Where frame k's square lies: it moves right 4 px and down 2 px a frame.
cv::Point squareAt(int k) {
  return {8 + 4 * k, 10 + 2 * k};
}

// Frame k as RGB: a grey-blue gradient with a red square at squareAt(k).
cv::Mat frameRgb(int width, int height, int k) {
  cv::Mat rgb(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) rgb.at<cv::Vec3b>(y, x) = {60, uint8_t(80 + y / 2), 160};
  }
  cv::rectangle(rgb, cv::Rect(squareAt(k), cv::Size(kSquare, kSquare)), {230, 30, 30}, cv::FILLED);
  return rgb;
}

// The red square's centre in a BGR frame read back: the mean of its strongly red pixels.
cv::Point2d redCentre(const cv::Mat& bgr) {
  cv::Mat red;
  cv::inRange(bgr, cv::Scalar(0, 0, 170), cv::Scalar(90, 90, 255), red);
  const cv::Moments m = cv::moments(red, true);
  return m.m00 > 0 ? cv::Point2d(m.m10 / m.m00, m.m01 / m.m00) : cv::Point2d(-1, -1);
}

// Writes `frames` frames, reads every one back through OpenCV's FFmpeg reader and checks each
// against what was written: PSNR over `min_psnr` dB, the square where it was.
void expectReadsBack(const std::filesystem::path& file, int width, int height, int frames,
                     double min_psnr) {
  cv::VideoCapture video(file.string(), cv::CAP_FFMPEG);
  ASSERT_TRUE(video.isOpened()) << file;
  cv::Mat frame, expected;
  int k = 0;
  while (video.read(frame)) {
    ASSERT_LT(k, frames) << "more frames than written";
    ASSERT_EQ(frame.cols, width & ~1);
    ASSERT_EQ(frame.rows, height & ~1);
    cv::cvtColor(frameRgb(width, height, k)(cv::Rect(0, 0, width & ~1, height & ~1)), expected,
                 cv::COLOR_RGB2BGR);
    EXPECT_GT(cv::PSNR(frame, expected), min_psnr) << "frame " << k;
    const cv::Point2d centre = redCentre(frame);
    const cv::Point at = squareAt(k);
    EXPECT_NEAR(centre.x, at.x + (kSquare - 1) / 2.0, 1.0) << "frame " << k;
    EXPECT_NEAR(centre.y, at.y + (kSquare - 1) / 2.0, 1.0) << "frame " << k;
    ++k;
  }
  EXPECT_EQ(k, frames) << "frames read back";
}

TEST(VideoFile, Mp4IsH264WithEveryFrameAtItsRateAndPlace) {
  const std::filesystem::path file = testFolder("video_file") / "square.mp4";
  VideoFileWriter writer(file, 192, 128, 25);
  EXPECT_EQ(writer.codec(), VideoCodec::kH264);
  EXPECT_EQ(writer.encoderName(), "libx264") << writer.warning();
  for (int k = 0; k < 30; ++k) writer.write(frameRgb(192, 128, k).data, PixelOrder::kRgb);
  writer.close();
  EXPECT_EQ(writer.framesWritten(), 30);
  const VideoFileInfo info = probeVideoFile(file);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_NE(info.container.find("mp4"), std::string::npos) << info.container;
  EXPECT_EQ(info.width, 192);
  EXPECT_EQ(info.height, 128);
  EXPECT_DOUBLE_EQ(info.fps, 25);
  EXPECT_EQ(info.frames, 30);
  expectReadsBack(file, 192, 128, 30, 32);
  // OpenCV's reader agrees on the rate and count (the MP4's index).
  cv::VideoCapture video(file.string(), cv::CAP_FFMPEG);
  EXPECT_DOUBLE_EQ(video.get(cv::CAP_PROP_FPS), 25);
  EXPECT_EQ(video.get(cv::CAP_PROP_FRAME_COUNT), 30);
}

TEST(VideoFile, AviIsMotionJpegAndRatesNeedNotBeWhole) {
  const std::filesystem::path file = testFolder("video_file") / "square.avi";
  {
    VideoFileWriter writer(file, 192, 128, 29.97);
    EXPECT_EQ(writer.encoderName(), "mjpeg");
    // BGRA rows with padding at their ends: the stride is honoured.
    for (int k = 0; k < 12; ++k) {
      cv::Mat bgra, padded(128, 200, CV_8UC4, cv::Scalar(0, 255, 0, 255));
      cv::cvtColor(frameRgb(192, 128, k), bgra, cv::COLOR_RGB2BGRA);
      bgra.copyTo(padded(cv::Rect(0, 0, 192, 128)));
      writer.write(padded.data, PixelOrder::kBgra, int(padded.step[0]));
    }
  }  // closed by its destructor
  const VideoFileInfo info = probeVideoFile(file);
  EXPECT_EQ(info.codec, "mjpeg");
  EXPECT_EQ(info.container, "avi");
  EXPECT_NEAR(info.fps, 29.97, 1e-3);
  EXPECT_EQ(info.frames, 12);
  expectReadsBack(file, 192, 128, 12, 32);
}

// 4:2:0 needs even sizes: an odd last column and row are left out, the rest is as written.
TEST(VideoFile, OddSizesLoseTheirLastColumnAndRow) {
  const std::filesystem::path file = testFolder("video_file") / "odd.mp4";
  VideoFileWriter writer(file, 161, 121, 30);
  EXPECT_EQ(writer.width(), 160);
  EXPECT_EQ(writer.height(), 120);
  for (int k = 0; k < 10; ++k) writer.write(frameRgb(161, 121, k).data, PixelOrder::kRgb);
  writer.close();
  const VideoFileInfo info = probeVideoFile(file);
  EXPECT_EQ(info.width, 160);
  EXPECT_EQ(info.height, 120);
  expectReadsBack(file, 161, 121, 10, 32);
}

TEST(VideoFile, WhatCannotBeWrittenIsAnErrorNamingTheFile) {
  const std::filesystem::path dir = testFolder("video_file_errors");
  const std::string missing = (dir / "missing" / "x.mp4").string();
  EXPECT_NE(errorOf([&] {
              VideoFileWriter(missing, 64, 48, 30);
            }).find(missing + ": cannot create the video file (No such file or directory)"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              VideoFileWriter(dir / "x.webm", 64, 48, 30);
            }).find("x.webm: expected a video file ending in .mp4 or .avi"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { VideoFileWriter(dir / "x.mp4", 1, 48, 30); }).find("at least 2x2"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { VideoFileWriter(dir / "x.mp4", 64, 48, 0); }).find("0 to 1000"),
            std::string::npos);
  // A full disk (/dev/full: every write fails with ENOSPC) is said, at the latest by close().
  const std::string full = errorOf([&] {
    VideoFileWriter writer("/dev/full", 64, 48, 30, VideoCodec::kMjpeg);
    const cv::Mat rgb = frameRgb(64, 48, 0);
    for (int k = 0; k < 50; ++k) writer.write(rgb.data, PixelOrder::kRgb);
    writer.close();
  });
  EXPECT_EQ(full.find("/dev/full: "), 0u) << full;
  EXPECT_NE(full.find("No space left on device"), std::string::npos) << full;
  // Nothing is added once closed.
  VideoFileWriter writer(dir / "closed.mp4", 64, 48, 30);
  writer.close();
  const cv::Mat rgb = frameRgb(64, 48, 0);
  EXPECT_NE(errorOf([&] { writer.write(rgb.data, PixelOrder::kRgb); }).find("closed"),
            std::string::npos);
}

// A live recording is a fragmented MP4, a key frame and a fragment a second: killed before it
// closes (no trailer), it still plays its whole seconds.
TEST(VideoFile, ALiveMp4KilledBeforeClosingPlaysItsWholeSeconds) {
  const std::filesystem::path file = testFolder("video_file_killed") / "live.mp4";
  const int result = testing::inChildProcess([&] {
    VideoFileWriter writer(file, 192, 128, 25, VideoCodec::kH264, VideoSpeed::kLive);
    for (int k = 0; k < 90; ++k) writer.write(frameRgb(192, 128, k % 30).data, PixelOrder::kRgb);
    ::_exit(0);  // as a crash: no close, no destructor
    return 1;
  });
  ASSERT_EQ(result, 0);
  const VideoFileInfo info = probeVideoFile(file);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_GE(info.frames, 50);  // frames 0-74 are in three whole fragments; the encoder may hold
  EXPECT_LE(info.frames, 90);  // the last few
  EXPECT_EQ(info.frames % 25, 0) << "whole fragments of a second";
}

}  // namespace
}  // namespace lumistage
