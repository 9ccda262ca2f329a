#pragma once

// What the view recorder's tests write and read back: solid RGBA frames, and every frame of a
// video as its mean colour.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <opencv2/videoio.hpp>
#include <vector>

namespace lumistage::testing {

inline std::vector<uint8_t> solid(int width, int height, uint8_t r, uint8_t g, uint8_t b) {
  std::vector<uint8_t> rgba(size_t(width) * height * 4, 255);
  for (size_t p = 0; p < rgba.size(); p += 4) {
    rgba[p] = r;
    rgba[p + 1] = g;
    rgba[p + 2] = b;
  }
  return rgba;
}

// Every frame of the video through OpenCV's reader `api` (cv::CAP_OPENCV_MJPEG, cv::CAP_FFMPEG),
// as the mean B, G, R of each; `size` the last frame's.
inline std::vector<cv::Scalar> readBack(const std::filesystem::path& file, cv::Size* size,
                                        int api) {
  cv::VideoCapture video(file.string(), api);
  EXPECT_TRUE(video.isOpened()) << file;
  std::vector<cv::Scalar> means;
  cv::Mat frame;
  while (video.read(frame)) {
    *size = frame.size();
    means.push_back(cv::mean(frame));
  }
  return means;
}

}  // namespace lumistage::testing
