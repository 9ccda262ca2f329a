// The real acquisition path: Aravis clients streaming over GigE Vision (GVCP/GVSP on UDP) from
// Aravis's fake cameras on loopback addresses. Runs inside its own network namespace (see
// tests/CMakeLists.txt), where the loopback addresses 127.0.1.x can be added freely.
#include <arv.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include "core/base/error.h"
#include "core/capture/aravis_source.h"
#include "core/capture/virtual_gige_cameras.h"
#include "core/geometry/ring_rig.h"

namespace lumistage {
namespace {

Rig smallRig(int cameras, int width, int height) {
  RingRigSpec spec;
  spec.cameras = cameras;
  spec.width = width;
  spec.height = height;
  return makeRingRig(spec);
}

std::shared_ptr<FrameLoop> randomLoop(const Rig& rig, int length, double fps, PixelFormat format) {
  auto loop = std::make_shared<FrameLoop>();
  loop->fps = fps;
  std::mt19937 rng(5);
  for (const Camera& camera : rig.cameras()) {
    loop->frames.emplace_back();
    for (int f = 0; f < length; ++f) {
      Image image;
      image.resize(format, camera.width(), camera.height());
      for (uint8_t& p : image.pixels) p = static_cast<uint8_t>(rng());
      loop->frames.back().push_back(std::move(image));
    }
  }
  return loop;
}

// GigE Vision 1.x block ids wrap from 65535 to 1: the ids count on (and a frame lost across the
// wrap still leaves its gap); 64-bit ids pass as they are.
TEST(Aravis, FrameIdsCountOnAcrossTheSixteenBitWrap) {
  FrameIdUnwrapper unwrap;
  std::vector<int64_t> ids;
  for (int64_t raw : {65533, 65534, 65535, 1, 2, 4}) ids.push_back(unwrap(raw));
  EXPECT_EQ(ids, (std::vector<int64_t>{65533, 65534, 65535, 65536, 65537, 65539}));
  FrameIdUnwrapper again;
  for (int64_t raw : {65000, 30, 32000, 65534, 2}) ids.push_back(again(raw));
  EXPECT_EQ(std::vector<int64_t>(ids.end() - 5, ids.end()),
            (std::vector<int64_t>{65000, 65565, 97535, 131069, 131072}));
  FrameIdUnwrapper wide;
  EXPECT_EQ(wide(70000), 70000);
  EXPECT_EQ(wide(5), 5);  // after a 64-bit id, no wrap is assumed
}

// Frame 5 arrives broken (missing packets), 6 whole: one frame dropped, not two; 8 and 9 never
// arrive: two more.
TEST(Aravis, ABrokenFrameIsOneDropNotTwo) {
  DropCounter drops;
  int64_t dropped = 0;
  for (int64_t id : {3, 4}) dropped += drops.whole(id);
  dropped += drops.broken();
  dropped += drops.whole(6);
  EXPECT_EQ(dropped, 1);
  dropped += drops.whole(7);
  dropped += drops.whole(10);
  EXPECT_EQ(dropped, 3);
  // Broken frames beyond the gap (a resent frame delivered broken twice) never make it negative.
  dropped += drops.broken();
  dropped += drops.broken();
  dropped += drops.whole(11);
  EXPECT_EQ(dropped, 5);
}

// A receive buffer limit that cannot hold two images is named with the sysctl that raises it;
// one that can says nothing. And the limit is what the kernel says.
TEST(Aravis, ASmallReceiveBufferLimitIsToldWithItsRemedy) {
  constexpr int64_t kImage = 1024 * 768;                           // the reference camera, Bayer
  const std::string advice = receiveBufferAdvice(212992, kImage);  // a stock kernel's
  EXPECT_NE(advice.find("net.core.rmem_max is 208 KB, less than two of the cameras' 768 KB "
                        "images"),
            std::string::npos)
      << advice;
  EXPECT_NE(advice.find("sudo sysctl -w net.core.rmem_max=33554432"), std::string::npos);
  EXPECT_EQ(receiveBufferAdvice(2 * kImage, kImage), "");
  EXPECT_NE(receiveBufferAdvice(2 * kImage - 1, kImage), "");
  EXPECT_EQ(receiveBufferAdvice(-1, kImage), "");  // unknown: no advice
  EXPECT_EQ(receiveBufferAdvice(1000, 0), "");     // no GigE Vision camera
  std::ifstream in("/proc/sys/net/core/rmem_max");
  int64_t limit = -1;
  in >> limit;
  EXPECT_EQ(receiveBufferLimit(), limit);
  EXPECT_GT(limit, 0);
}

TEST(Aravis, VirtualCamerasStreamTheSyntheticFramesBitExact) {
  const Rig rig = smallRig(2, 320, 240);
  const double fps = 50;
  auto loop = randomLoop(rig, 7, fps, PixelFormat::kBayerRggb8);
  VirtualGigeCameras server(rig, loop, PixelFormat::kBayerRggb8, "127.0.1.1");
  ASSERT_EQ(server.addresses(), (std::vector<std::string>{"127.0.1.1", "127.0.1.2"}));

  std::vector<AravisCameraConfig> configs(2);
  for (int c = 0; c < 2; ++c) {
    configs[c].device = server.addresses()[c];
    configs[c].frame_rate_hz = fps;
  }
  AravisSource source(rig, configs);
  CameraFrame frame;
  int received[2] = {0, 0};
  std::map<int64_t, std::vector<int64_t>> timestamps_by_id;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while ((received[0] < 100 || received[1] < 100) && std::chrono::steady_clock::now() < deadline) {
    if (!source.next(frame, std::chrono::milliseconds(500))) continue;
    ASSERT_GE(frame.camera, 0);
    ASSERT_LT(frame.camera, 2);
    ASSERT_EQ(frame.image.format, PixelFormat::kBayerRggb8);
    ASSERT_EQ(frame.image.width, 320);
    // The pixels are exactly the loop's frame of the instant the timestamp names.
    const Image& sent =
        loop->frames[frame.camera][loopFrameAt(frame.timestamp_ns, fps, loop->length())];
    if (frame.image.pixels != sent.pixels) {
      // Which frame it is instead: of another instant, of the other camera, or none (a torn
      // frame). Seen once under CI load on camera 1, the second opened (AravisSource now opens
      // every stream before any camera sends).
      std::string instead = "no frame of the loop";
      for (int c = 0; c < 2; ++c)
        for (int k = 0; k < loop->length(); ++k)
          if (loop->frames[c][k].pixels == frame.image.pixels)
            instead = "camera " + std::to_string(c) + "'s loop frame " + std::to_string(k);
      FAIL() << "camera " << frame.camera << " frame " << frame.frame_id << " stamped "
             << frame.timestamp_ns << " ns should hold loop frame "
             << loopFrameAt(frame.timestamp_ns, fps, loop->length()) << " but holds " << instead;
    }
    timestamps_by_id[frame.frame_id].push_back(frame.timestamp_ns);
    ++received[frame.camera];
  }
  EXPECT_GE(received[0], 100);
  EXPECT_GE(received[1], 100);
  // Frames of one instant carry the same id and timestamp on every camera: grouping is exact.
  int shared = 0;
  for (const auto& [id, stamps] : timestamps_by_id) {
    if (stamps.size() == 2) {
      EXPECT_EQ(stamps[0], stamps[1]) << "frame id " << id;
      ++shared;
    }
  }
  EXPECT_GT(shared, 50);  // most instants reached both cameras (a loaded machine loses some)
  const CameraStats stats = source.stats(0);
  EXPECT_GE(stats.frames, 100);
  EXPECT_GT(stats.frame_rate_hz, 0.0);  // measured; its value is a benchmark's business
}

TEST(Aravis, ClientChoosesAnotherBayerLayoutAndGetsItExactly) {
  // Frames held as RGB; the client asks for BayerGR8: the virtual camera mosaics exactly.
  const Rig rig = smallRig(1, 160, 120);
  auto loop = randomLoop(rig, 4, 25, PixelFormat::kRgb8);
  VirtualGigeCameras server(rig, loop, PixelFormat::kRgb8, "127.0.1.6");
  AravisCameraConfig config;
  config.device = server.addresses()[0];
  config.pixel_format = PixelFormat::kBayerGrbg8;
  AravisSource source(rig, {config});
  CameraFrame frame;
  int checked = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (checked < 10 && std::chrono::steady_clock::now() < deadline) {
    if (!source.next(frame, std::chrono::milliseconds(300))) continue;
    ASSERT_EQ(frame.image.format, PixelFormat::kBayerGrbg8);
    const Image& sent = loop->frames[0][loopFrameAt(frame.timestamp_ns, 25, loop->length())];
    std::vector<uint8_t> rgba(size_t(160) * 120 * 4);
    for (size_t p = 0; p < size_t(160) * 120; ++p) {
      for (int k = 0; k < 3; ++k) rgba[4 * p + k] = sent.pixels[3 * p + k];
    }
    Image expected;
    rgbaToImage(rgba.data(), 160, 120, PixelFormat::kBayerGrbg8, expected);
    ASSERT_EQ(frame.image.pixels, expected.pixels);
    ++checked;
  }
  EXPECT_EQ(checked, 10);
}

TEST(Aravis, SoftwareTriggerFiresEveryCamera) {
  const Rig rig = smallRig(2, 160, 120);
  auto loop = randomLoop(rig, 3, 25, PixelFormat::kMono8);
  VirtualGigeCameras server(rig, loop, PixelFormat::kMono8, "127.0.1.4");
  std::vector<AravisCameraConfig> configs(2);
  for (int c = 0; c < 2; ++c) {
    configs[c].device = server.addresses()[c];
    configs[c].pixel_format = PixelFormat::kMono8;
    configs[c].trigger = TriggerMode::kSoftware;
  }
  AravisSource source(rig, configs);
  CameraFrame frame;
  // Untriggered, the cameras stay quiet.
  EXPECT_FALSE(source.next(frame, std::chrono::milliseconds(600)));
  // Each trigger fires both cameras. UDP on a loaded machine may lose a frame now and then (it
  // is counted as dropped), so fire up to twice as often as needed for five frames each.
  int received[2] = {0, 0}, triggers = 0;
  while ((received[0] < 5 || received[1] < 5) && triggers < 10) {
    source.trigger();
    ++triggers;
    const int before = received[0] + received[1];
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (received[0] + received[1] < before + 2 && std::chrono::steady_clock::now() < deadline) {
      if (source.next(frame, std::chrono::milliseconds(100))) ++received[frame.camera];
    }
  }
  EXPECT_GE(received[0], 5);
  EXPECT_GE(received[1], 5);
  EXPECT_LE(received[0], triggers);  // never more frames than triggers: the cameras wait for them
  EXPECT_LE(received[1], triggers);
}

TEST(Aravis, ConfiguresAravisOwnFakeCameraProgram) {
  // Aravis's own fake GigE Vision camera, as a separate process.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    execlp("arv-fake-gv-camera-0.8", "arv-fake-gv-camera-0.8", "-i", "127.0.1.9", "-s", "ARVFAKE9",
           static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // let it bind
  const Rig rig = smallRig(1, 640, 480);
  AravisCameraConfig config;
  config.device = "127.0.1.9";
  config.pixel_format = PixelFormat::kMono8;
  config.frame_rate_hz = 40;
  std::string error;
  int frames = 0;
  try {
    AravisSource source(rig, {config});
    CameraFrame frame;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (frames < 100 && std::chrono::steady_clock::now() < deadline) {
      if (!source.next(frame, std::chrono::milliseconds(500))) continue;
      EXPECT_EQ(frame.image.width, 640);
      EXPECT_EQ(frame.image.height, 480);
      ++frames;
    }
    // Its test pattern is a ramp: not one flat value.
    EXPECT_NE(*std::min_element(frame.image.pixels.begin(), frame.image.pixels.end()),
              *std::max_element(frame.image.pixels.begin(), frame.image.pixels.end()));
  } catch (const Error& e) {
    error = e.what();
  }
  kill(child, SIGTERM);
  waitpid(child, nullptr, 0);
  EXPECT_EQ(error, "");
  EXPECT_EQ(frames, 100);
}

TEST(Aravis, DiscoveryListsTheInProcessFakeInterface) {
  arv_enable_interface("Fake");
  const std::vector<AravisDeviceInfo> devices = discoverAravisCameras();
  bool fake = false;
  for (const AravisDeviceInfo& d : devices) fake = fake || d.protocol == "Fake";
  EXPECT_TRUE(fake);
}

// Frames of each camera that arrive within `seconds`.
std::array<int, 2> framesWithin(AravisSource& source, double seconds) {
  std::array<int, 2> received{0, 0};
  CameraFrame frame;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline)
    if (source.next(frame, std::chrono::milliseconds(100)) && frame.camera >= 0 && frame.camera < 2)
      ++received[frame.camera];
  return received;
}

// A node's camera that cannot be opened (not powered, wrong address) leaves the others streaming:
// it is named in its stats and tried again, not the end of the node.
TEST(Aravis, ACameraThatCannotBeOpenedLeavesTheOthersStreaming) {
  const Rig rig = smallRig(2, 160, 120);
  auto loop = randomLoop(rig, 3, 25, PixelFormat::kMono8);
  VirtualGigeCameras server(rig, loop, PixelFormat::kMono8, "127.0.1.12");
  std::vector<AravisCameraConfig> configs(2);
  configs[0].device = server.addresses()[0];
  configs[1].device = "127.0.1.78";  // nobody serves there
  for (AravisCameraConfig& c : configs) c.pixel_format = PixelFormat::kMono8;
  AravisSource source(rig, configs);
  const std::array<int, 2> received = framesWithin(source, 2.0);
  EXPECT_GT(received[0], 10);
  EXPECT_EQ(received[1], 0);
  EXPECT_NE(source.stats(1).last_error.find("camera cam02 (127.0.1.78): cannot open"),
            std::string::npos)
      << source.stats(1).last_error;
}

// The cameras go away (powered off, unplugged) and come back: each is opened again by itself and
// streams again, its frame ids lined up with the others'.
TEST(Aravis, CamerasThatComeBackStreamAgain) {
  const Rig rig = smallRig(2, 160, 120);
  auto loop = randomLoop(rig, 3, 25, PixelFormat::kMono8);
  std::vector<AravisCameraConfig> configs(2);
  auto server = std::make_unique<VirtualGigeCameras>(rig, loop, PixelFormat::kMono8, "127.0.1.14");
  for (int c = 0; c < 2; ++c) {
    configs[c].device = server->addresses()[c];
    configs[c].pixel_format = PixelFormat::kMono8;
  }
  AravisSource source(rig, configs);
  std::array<int, 2> received = framesWithin(source, 1.5);
  ASSERT_GT(received[0], 5);
  ASSERT_GT(received[1], 5);
  // The newest frame before the cameras go, and when.
  CameraFrame frame;
  int64_t last_id = -1;
  for (int k = 0; k < 10; ++k) {
    if (source.next(frame, std::chrono::milliseconds(100))) last_id = frame.frame_id;
  }
  const auto gone = std::chrono::steady_clock::now();
  server.reset();             // gone
  framesWithin(source, 7.0);  // long enough to be taken for lost
  EXPECT_EQ(source.stats(0).frame_rate_hz, 0.0);
  server = std::make_unique<VirtualGigeCameras>(rig, loop, PixelFormat::kMono8, "127.0.1.14");
  // Back within a retry or two; from then on, frames of one instant share their id again.
  std::map<int64_t, int> cameras_of_id;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  received = {0, 0};
  int64_t first_id = -1;
  double first_after_s = 0;
  while (std::chrono::steady_clock::now() < deadline && (received[0] < 30 || received[1] < 30)) {
    if (!source.next(frame, std::chrono::milliseconds(100))) continue;
    if (first_id < 0) {
      first_id = frame.frame_id;
      first_after_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - gone).count();
    }
    ++received[frame.camera];
    ++cameras_of_id[frame.frame_id];
  }
  // Their ids went on counting the instants while they were gone (25 a second), as the other
  // nodes' cameras' did: not on from the last frame before.
  ASSERT_GE(first_id, 0);
  EXPECT_NEAR(double(first_id - last_id), first_after_s * 25, 6)
      << "back after " << first_after_s << " s";
  EXPECT_GE(received[0], 30);
  EXPECT_GE(received[1], 30);
  int shared = 0;
  for (const auto& [id, n] : cameras_of_id) shared += n == 2;
  EXPECT_GT(shared, 10) << "the cameras' ids no longer meet";
  EXPECT_EQ(source.stats(0).last_error, "");
}

TEST(Aravis, ClearErrorsNameTheCameraAndAddress) {
  const Rig rig = smallRig(1, 320, 240);
  AravisCameraConfig config;
  config.device = "127.0.1.77";  // nobody serves there
  try {
    AravisSource source(rig, {config});
    FAIL() << "opened a camera that does not exist";
  } catch (const Error& e) {
    // Told by the camera's own address not answering (GigE Vision discovery, in half a second),
    // not after Aravis's retries, which it runs for one camera at a time.
    EXPECT_NE(std::string(e.what()).find("camera cam01 (127.0.1.77): cannot open: no GigE Vision "
                                         "device answers at 127.0.1.77"),
              std::string::npos)
        << e.what();
  }
  auto loop = randomLoop(rig, 1, 25, PixelFormat::kMono8);
  try {
    VirtualGigeCameras server(rig, loop, PixelFormat::kMono8, "10.254.254.1");
    FAIL() << "served on an address this machine does not have";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("10.254.254.1 is not an address of this machine"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lumistage
