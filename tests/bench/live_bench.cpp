// Micro-benchmarks of the live feeds out of the studio: what each adds to a frame shown. Run:
// ./studio bench (the target: under 5 ms a frame at the studio).
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <utility>
#include <vector>

#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"
#include "core/live/v4l2_output.h"
#include "core/live/video_feed.h"
#include "core/live/vmc_sender.h"
#include "tests/feed_receiver.h"

namespace {

// The studio's pose messages of a walk, as the nodes get them.
std::vector<lumistage::PoseData> walkPoses(const lumistage::Skeleton& skeleton) {
  const lumistage::MotionClip clip = lumistage::makeBuiltinClip("walk", skeleton, 30, 2);
  std::vector<lumistage::PoseData> poses;
  for (const lumistage::Pose& pose : clip.frames) {
    lumistage::PoseData data;
    for (int k = 0; k < 3; ++k) data.root[k] = float(pose.root_translation_m[k]);
    for (const Eigen::Vector3d& a : pose.angles_rad)
      data.angles.insert(data.angles.end(), {float(a.x()), float(a.y()), float(a.z())});
    poses.push_back(std::move(data));
  }
  return poses;
}

// A UDP port on 127.0.0.1: bound (a receiver there, never read: the kernel drops what overflows
// its buffer, the sender's cost is the same), or closed (nobody there).
struct LoopbackPort {
  int socket = -1, port = 0;
  explicit LoopbackPort(bool keep) {
    socket = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof(address);
    ::bind(socket, reinterpret_cast<sockaddr*>(&address), size);
    ::getsockname(socket, reinterpret_cast<sockaddr*>(&address), &size);
    port = ntohs(address.sin_port);
    if (!keep) ::close(std::exchange(socket, -1));
  }
  ~LoopbackPort() {
    if (socket >= 0) ::close(socket);
  }
};

// One frame's VMC bundle: the bones' local poses in Unity's axes, the OSC bundle serialised by
// liblo, one sendto() on loopback. Arg 1: a receiver bound to the port; 0: none there.
void vmcSendFrame(benchmark::State& state) {
  const lumistage::Skeleton skeleton = lumistage::makeHumanSkeleton();
  const std::vector<lumistage::PoseData> poses = walkPoses(skeleton);
  const LoopbackPort port(state.range(0) != 0);
  lumistage::VmcSender sender({"127.0.0.1", port.port}, skeleton);
  size_t f = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sender.send(poses[f++ % poses.size()], true));
  state.counters["bones"] = double(sender.bones().size());
  state.counters["bytes"] = double(sender.bundleBytes());
  state.counters["lost"] = double(sender.bundlesLost());
}
BENCHMARK(vmcSendFrame)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

// The view's live feed at 640x480, 30 pictures a second of an actor-like blob moving over black,
// to a UDP port on 127.0.0.1 nobody reads. What is timed: offer(), the studio thread's part (the
// picture copied and handed over); the pace between pictures is not. Counters: the feed thread's
// time a picture to encode (libx264, its threads included) and send (`send_ms`), and the pictures
// it dropped (none, unless it could not keep up).
void videoFeedOffer(benchmark::State& state) {
  constexpr int kWidth = 640, kHeight = 480;
  const LoopbackPort port(true);
  lumistage::VideoFeed feed(lumistage::parseFeedUrl("udp://127.0.0.1:" + std::to_string(port.port)),
                            kWidth, kHeight, 30);
  std::vector<std::vector<uint8_t>> pictures(30,
                                             std::vector<uint8_t>(size_t(kWidth) * kHeight * 4));
  for (int k = 0; k < 30; ++k) {
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const int dx = x - 200 - 8 * k, dy = y - 240;
        if (dx * dx / 4 + dy * dy >= 20000) continue;
        uint8_t* p = &pictures[size_t(k)][(size_t(y) * kWidth + x) * 4];
        p[0] = uint8_t(100 + (x + 3 * k) % 80), p[1] = uint8_t(60 + y % 90);
        p[2] = uint8_t(50 + (x ^ y) % 40), p[3] = 255;
      }
    }
  }
  size_t f = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(feed.offer(kWidth, kHeight, pictures[f++ % pictures.size()]));
    state.PauseTiming();
    std::this_thread::sleep_for(std::chrono::milliseconds(33));
    state.ResumeTiming();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the last picture sent
  state.counters["send_ms"] = feed.sendMs();
  state.counters["sent"] = double(feed.framesSent());
  state.counters["dropped"] = double(feed.framesDropped());
}
BENCHMARK(videoFeedOffer)->Unit(benchmark::kMicrosecond)->Iterations(90)->UseRealTime();

// What a feed to a v4l2loopback device does to a picture besides write() (a copy into the
// device's buffer): a 640x480 RGBA picture to I420 of the device's size, on the feed's thread.
// Arg: the device's width (640: the same size; 1280: scaled up to 1280x960).
void v4l2Convert(benchmark::State& state) {
  constexpr int kWidth = 640, kHeight = 480;
  const int width = int(state.range(0));
  lumistage::V4l2Output output(width, width * 3 / 4);
  std::vector<uint8_t> picture(size_t(kWidth) * kHeight * 4);
  for (size_t k = 0; k < picture.size(); ++k) picture[k] = uint8_t(k * 7 + k / 2560);
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        output.convert(picture.data(), lumistage::PixelOrder::kRgba, kWidth, kHeight).data());
  }
}
BENCHMARK(v4l2Convert)->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);

// The feed's latency at a receiver on the same PC: from offer() to the picture out of the
// receiver's decoder (FFmpeg's, set for latency as `ffplay -fflags nobuffer -flags low_delay` is),
// 640x480 at 30 pictures a second for 6 s over UDP on loopback. Each picture carries its number in
// a row of black and white 32-pixel blocks, read back from the decoded picture. The first second is
// left out (the receiver analyses the stream before its first picture). Counters: the latency's
// median, 95th percentile and most (ms), and the pictures received.
void videoFeedLatency(benchmark::State& state) {
  constexpr int kWidth = 640, kHeight = 480, kBits = 10, kBlock = 32, kPictures = 180, kSkip = 30;
  for (auto _ : state) {
    const int port = lumistage::testing::freeUdpPort();
    lumistage::testing::FeedReceiver receiver("udp://127.0.0.1:" + std::to_string(port), kPictures,
                                              std::chrono::seconds(10), true);
    lumistage::testing::waitForUdpPort(port, std::chrono::seconds(5));
    lumistage::VideoFeed feed(lumistage::parseFeedUrl("udp://127.0.0.1:" + std::to_string(port)),
                              kWidth, kHeight, 30);
    std::vector<uint8_t> picture(size_t(kWidth) * kHeight * 4);
    std::vector<std::chrono::steady_clock::time_point> offered(kPictures);
    auto next = std::chrono::steady_clock::now();
    for (int k = 0; k < kPictures; ++k) {
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
          uint8_t* p = &picture[(size_t(y) * kWidth + x) * 4];
          const int bit = x / kBlock;
          const bool white = y < kBlock && bit < kBits && ((k >> bit) & 1);
          const int dx = x - 200 - 2 * k, dy = y - 260;  // an actor-like blob moving
          const bool blob = dx * dx / 4 + dy * dy < 20000;
          p[0] = white ? 255 : blob ? uint8_t(100 + (x + 3 * k) % 80) : 0;
          p[1] = white ? 255 : blob ? uint8_t(60 + y % 90) : 0;
          p[2] = white ? 255 : blob ? uint8_t(50 + (x ^ y) % 40) : 0;
          p[3] = 255;
        }
      }
      std::this_thread::sleep_until(next);
      offered[size_t(k)] = std::chrono::steady_clock::now();
      feed.offer(kWidth, kHeight, picture);
      next += std::chrono::microseconds(33333);
    }
    const std::vector<lumistage::testing::DecodedPicture> received = receiver.wait();
    std::vector<double> latency_ms;
    for (const lumistage::testing::DecodedPicture& r : received) {
      if (r.width != kWidth || r.height != kHeight) continue;
      int k = 0;
      for (int bit = 0; bit < kBits; ++bit)
        if (r.at(bit * kBlock + kBlock / 2, kBlock / 2)[0] > 128) k |= 1 << bit;
      // The last picture leaves the receiver's H.264 parser only when the stream ends: a picture
      // is whole when the next one begins.
      if (k < kSkip || k >= kPictures - 1) continue;
      latency_ms.push_back(
          std::chrono::duration<double, std::milli>(r.decoded_at - offered[size_t(k)]).count());
    }
    std::sort(latency_ms.begin(), latency_ms.end());
    const auto at = [&](double q) {
      return latency_ms.empty() ? 0.0 : latency_ms[size_t(q * double(latency_ms.size() - 1))];
    };
    state.counters["latency_ms_p50"] = at(0.5);
    state.counters["latency_ms_p95"] = at(0.95);
    state.counters["latency_ms_max"] = at(1.0);
    state.counters["received"] = double(received.size());
  }
}
BENCHMARK(videoFeedLatency)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace
