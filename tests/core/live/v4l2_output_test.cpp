// The view to a video4linux2 output device: its pictures as I420, the devices it refuses and why,
// and (where the machine has a v4l2loopback device) the pictures a webcam reader gets back.
#include "core/live/v4l2_output.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "core/live/video_feed.h"
#include "tests/quadrant_picture.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using namespace std::chrono_literals;
using testing::testFolder;

constexpr int kWidth = testing::kQuadrantsWidth, kHeight = testing::kQuadrantsHeight;
constexpr auto& kColours = testing::kQuadrantColours;
using testing::quadrants;

// Each quadrant's middle in an I420 picture of width x height holds its colour in BT.601 limited
// range (Rec. 601's matrix: Y 16-235, Cb and Cr 16-240).
void expectTheQuadrantsInI420(const uint8_t* i420, int width, int height) {
  const uint8_t* u_plane = i420 + size_t(width) * height;
  const uint8_t* v_plane = u_plane + size_t(width / 2) * (height / 2);
  for (int q = 0; q < 4; ++q) {
    const double r = kColours[q][0], g = kColours[q][1], b = kColours[q][2];
    const double y = 16 + (65.481 * r + 128.553 * g + 24.966 * b) / 255;
    const double u = 128 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255;
    const double v = 128 + (112.0 * r - 93.786 * g - 18.214 * b) / 255;
    const int x = (q % 2) * width / 2 + width / 4, row = (q / 2) * height / 2 + height / 4;
    EXPECT_NEAR(i420[size_t(row) * width + x], y, 2) << "quadrant " << q;
    EXPECT_NEAR(u_plane[size_t(row / 2) * (width / 2) + x / 2], u, 2) << "quadrant " << q;
    EXPECT_NEAR(v_plane[size_t(row / 2) * (width / 2) + x / 2], v, 2) << "quadrant " << q;
  }
}

TEST(V4l2Output, ConvertsPicturesToI420OfItsOwnSize) {
  const std::vector<uint8_t> rgba = quadrants();
  V4l2Output same(kWidth, kHeight);
  const std::span<const uint8_t> full =
      same.convert(rgba.data(), PixelOrder::kRgba, kWidth, kHeight);
  ASSERT_EQ(full.size(), size_t(kWidth) * kHeight * 3 / 2);
  expectTheQuadrantsInI420(full.data(), kWidth, kHeight);
  // Another size, and an odd one: scaled to the output's, its last column and row left out.
  V4l2Output half(161, 121);
  EXPECT_EQ(half.width(), 160);
  EXPECT_EQ(half.height(), 120);
  const std::span<const uint8_t> small =
      half.convert(rgba.data(), PixelOrder::kRgba, kWidth, kHeight);
  ASSERT_EQ(small.size(), size_t(160) * 120 * 3 / 2);
  expectTheQuadrantsInI420(small.data(), 160, 120);
  // BGR rows with padding at their ends.
  const int stride = kWidth * 3 + 8;
  std::vector<uint8_t> bgr(size_t(stride) * kHeight, 0);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const uint8_t* p = &rgba[(size_t(y) * kWidth + x) * 4];
      uint8_t* q = &bgr[size_t(y) * stride + x * 3];
      q[0] = p[2], q[1] = p[1], q[2] = p[0];
    }
  }
  const std::span<const uint8_t> from_bgr =
      same.convert(bgr.data(), PixelOrder::kBgr, kWidth, kHeight, stride);
  expectTheQuadrantsInI420(from_bgr.data(), kWidth, kHeight);
}

TEST(V4l2Output, RefusesWhatIsNotAnOutputDeviceSayingWhy) {
  V4l2Output output(kWidth, kHeight);
  const std::filesystem::path folder = testFolder("v4l2_output");
  const std::string missing = (folder / "video99").string();
  const Status no_file = output.open(missing);
  ASSERT_FALSE(no_file.ok());
  EXPECT_NE(no_file.error().find(missing), std::string::npos) << no_file.error();
  EXPECT_NE(no_file.error().find("modprobe v4l2loopback"), std::string::npos) << no_file.error();
  const std::string file = (folder / "view.yuv").string();
  std::ofstream(file) << "not a device";
  const Status regular = output.open(file);
  ASSERT_FALSE(regular.ok());
  EXPECT_NE(regular.error().find("not a device"), std::string::npos) << regular.error();
  // A FIFO nobody reads: refused at once (opened non-blocking), not waited on.
  const std::string fifo = (folder / "fifo").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  const Status pipe = output.open(fifo);
  ::close(reader);
  ASSERT_FALSE(pipe.ok());
  EXPECT_NE(pipe.error().find("not a device"), std::string::npos) << pipe.error();
  const Status null = output.open("/dev/null");
  ASSERT_FALSE(null.ok());
  EXPECT_NE(null.error().find("not a V4L2 device"), std::string::npos) << null.error();
  EXPECT_FALSE(output.isOpen());
  bool taken = true;
  EXPECT_FALSE(output.write(quadrants().data(), PixelOrder::kRgba, kWidth, kHeight, taken).ok());
  EXPECT_FALSE(taken);
}

TEST(V4l2Output, AFeedToWhatIsNoDeviceStopsSayingWhy) {
  VideoFeed feed(parseFeedUrl("v4l2:///dev/null"), kWidth, kHeight, 25);
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (feed.status().ok() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  const Status status = feed.status();
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().find("v4l2:///dev/null"), std::string::npos) << status.error();
  EXPECT_NE(status.error().find("not a V4L2 device"), std::string::npos) << status.error();
  EXPECT_FALSE(feed.offer(kWidth, kHeight, quadrants()));
  EXPECT_EQ(feed.framesSent(), 0);
}

// The first v4l2loopback (or other output) device this machine has, or "".
std::string outputDevice() {
  for (int n = 0; n < 64; ++n) {
    const std::string device = "/dev/video" + std::to_string(n);
    if (access(device.c_str(), W_OK) != 0) continue;
    if (V4l2Output(kWidth, kHeight).open(device).ok()) return device;
  }
  return {};
}

TEST(V4l2Output, AWebcamReaderOfTheLoopbackDeviceGetsThePictures) {
  const std::string device = outputDevice();
  if (device.empty()) GTEST_SKIP() << "no v4l2loopback device (sudo modprobe v4l2loopback)";
  VideoFeed feed(parseFeedUrl("v4l2://" + device), kWidth, kHeight, 25);
  // The reader's side, as a webcam program reads it (read() I/O).
  const int reader = ::open(device.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0) << device;
  std::vector<uint8_t> picture(size_t(kWidth) * kHeight * 3 / 2);
  const std::vector<uint8_t> rgba = quadrants();
  ssize_t got = -1;
  for (int tries = 0; tries < 100 && got != ssize_t(picture.size()); ++tries) {
    feed.offer(kWidth, kHeight, rgba);
    pollfd ready{reader, POLLIN, 0};
    if (poll(&ready, 1, 100) == 1) got = read(reader, picture.data(), picture.size());
  }
  ::close(reader);
  ASSERT_EQ(got, ssize_t(picture.size())) << feed.status().error();
  expectTheQuadrantsInI420(picture.data(), kWidth, kHeight);
  EXPECT_TRUE(feed.status().ok()) << feed.status().error();
  EXPECT_GE(feed.framesSent(), 1);
  EXPECT_EQ(feed.encoderName(), "raw");
}

}  // namespace
}  // namespace lumistage
