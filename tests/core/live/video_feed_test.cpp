// The live video feed received as OBS or ffplay receives it: a real FFmpeg receiver on
// 127.0.0.1, over UDP and SRT, decoding what the feed sent.
#include "core/live/video_feed.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/base/error.h"
#include "tests/feed_receiver.h"
#include "tests/quadrant_picture.h"

namespace lumistage {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
using testing::DecodedPicture;
using testing::FeedReceiver;
using testing::freeUdpPort;

constexpr int kWidth = testing::kQuadrantsWidth, kHeight = testing::kQuadrantsHeight;
constexpr auto& kColours = testing::kQuadrantColours;
using testing::quadrants;

// Offers the picture at 25 a second while `more()` holds; the longest offer() took, ms.
template <typename More>
double feedWhile(VideoFeed& feed, More more) {
  const std::vector<uint8_t> picture = quadrants();
  double longest_ms = 0;
  while (more()) {
    const auto before = Clock::now();
    feed.offer(kWidth, kHeight, picture);
    longest_ms = std::max(longest_ms,
                          std::chrono::duration<double, std::milli>(Clock::now() - before).count());
    std::this_thread::sleep_for(40ms);
  }
  return longest_ms;
}

// Until the receiver has its pictures or gave up.
double feedUntilReceived(VideoFeed& feed, FeedReceiver& receiver) {
  return feedWhile(feed, [&] { return !receiver.finished(); });
}

// Each decoded picture is the one sent: its size, and each quadrant's colour at its middle (the
// codec's error: a few levels on flat colour).
void expectTheQuadrants(const std::vector<DecodedPicture>& pictures) {
  for (const DecodedPicture& p : pictures) {
    ASSERT_EQ(p.width, kWidth);
    ASSERT_EQ(p.height, kHeight);
    for (int q = 0; q < 4; ++q) {
      const int x = (q % 2) * kWidth / 2 + kWidth / 4, y = (q / 2) * kHeight / 2 + kHeight / 4;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(p.at(x, y)[c], kColours[q][c], 10) << "quadrant " << q << " channel " << c;
    }
  }
}

TEST(FeedUrl, ReadsUdpAndSrtTargets) {
  const FeedTarget udp = parseFeedUrl("udp://127.0.0.1:5000");
  EXPECT_EQ(udp.protocol, FeedTarget::Protocol::kUdp);
  EXPECT_EQ(udp.host, "127.0.0.1");
  EXPECT_EQ(udp.port, 5000);
  EXPECT_FALSE(udp.listener);
  const FeedTarget options = parseFeedUrl("UDP://239.0.0.1:1234?ttl=4&pkt_size=1316");
  EXPECT_EQ(options.host, "239.0.0.1");
  EXPECT_EQ(options.port, 1234);
  EXPECT_EQ(parseFeedUrl("udp://[::1]:7000").host, "::1");
  if (!ffmpegCanSend("srt")) GTEST_SKIP() << "this FFmpeg has no SRT";
  const FeedTarget caller = parseFeedUrl("srt://studio.local:9000?latency=200000");
  EXPECT_EQ(caller.protocol, FeedTarget::Protocol::kSrt);
  EXPECT_FALSE(caller.listener);
  const FeedTarget listener = parseFeedUrl("srt://:9000?mode=listener");
  EXPECT_TRUE(listener.listener);
  EXPECT_EQ(listener.host, "");
  EXPECT_EQ(listener.port, 9000);
}

TEST(FeedUrl, ReadsAV4l2DeviceByItsPath) {
  const FeedTarget device = parseFeedUrl("v4l2:///dev/video10");
  EXPECT_EQ(device.protocol, FeedTarget::Protocol::kV4l2);
  EXPECT_EQ(device.device, "/dev/video10");
  EXPECT_EQ(device.carries(), "uncompressed I420 to a video4linux2 device");
}

TEST(FeedUrl, RefusesWhatIsNoFeedSayingWhy) {
  const std::map<std::string, std::string> why{
      {"rtmp://host/live", "not 'rtmp'"},
      {"view.mp4", "not a URL"},
      {"udp://127.0.0.1", "no port"},
      {"udp://127.0.0.1:0", "not 1 to 65535"},
      {"udp://127.0.0.1:70000", "not 1 to 65535"},
      {"udp://:5000", "no host"},
      {"udp://host:5000/path", "no path"},
      {"udp://host:5000?mode=listener", "mode= is SRT's"},
      {"srt://host:5000?mode=rendezvous", "caller or listener"},
      {"v4l2://dev/video0", "whole path"},
      {"v4l2://", "whole path"},
  };
  for (const auto& [url, reason] : why) {
    try {
      parseFeedUrl(url);
      ADD_FAILURE() << url << " was taken";
    } catch (const Error& e) {
      const std::string text = e.what();
      // Where this FFmpeg lacks SRT, an srt:// URL is refused for that first.
      if (url.rfind("srt", 0) == 0 && !ffmpegCanSend("srt")) continue;
      EXPECT_NE(text.find(reason), std::string::npos) << url << ": " << text;
      EXPECT_NE(text.find("udp://HOST:PORT"), std::string::npos) << text;
    }
  }
}

TEST(VideoFeed, SendsThePictureOverUdpToAReceiverThatDecodesIt) {
  const int port = freeUdpPort();
  const std::string url = "udp://127.0.0.1:" + std::to_string(port);
  FeedReceiver receiver(url, 5);
  ASSERT_TRUE(testing::waitForUdpPort(port, 30s)) << "the receiver never bound " << url;
  VideoFeed feed(parseFeedUrl(url), kWidth, kHeight, 25);
  const double longest_ms = feedUntilReceived(feed, receiver);
  const std::vector<DecodedPicture> pictures = receiver.wait();
  ASSERT_EQ(pictures.size(), 5u) << receiver.error();
  expectTheQuadrants(pictures);
  EXPECT_EQ(feed.status().error(), "");
  EXPECT_TRUE(feed.connected());
  EXPECT_GE(feed.framesSent(), 5);
  EXPECT_EQ(feed.encoderName(), "libx264");
  // offer() copies a picture and returns: a bound far above that, for a loaded machine.
  EXPECT_LT(longest_ms, 250);
  feed.close();
  EXPECT_FALSE(feed.offer(kWidth, kHeight, quadrants()));
}

// A picture of another size than the feed's is scaled to it.
TEST(VideoFeed, ScalesAPictureOfAnotherSizeToTheFeeds) {
  const int port = freeUdpPort();
  const std::string url = "udp://127.0.0.1:" + std::to_string(port);
  FeedReceiver receiver(url, 2);
  ASSERT_TRUE(testing::waitForUdpPort(port, 30s));
  VideoFeed feed(parseFeedUrl(url), kWidth / 2, kHeight / 2, 25);
  const std::vector<uint8_t> picture = quadrants();
  while (!receiver.finished()) {
    feed.offer(kWidth, kHeight, picture);
    std::this_thread::sleep_for(40ms);
  }
  const std::vector<DecodedPicture> pictures = receiver.wait();
  ASSERT_EQ(pictures.size(), 2u) << receiver.error();
  for (const DecodedPicture& p : pictures) {
    ASSERT_EQ(p.width, kWidth / 2);
    ASSERT_EQ(p.height, kHeight / 2);
    EXPECT_NEAR(p.at(kWidth / 8, kHeight / 8)[0], kColours[0][0], 10);
    EXPECT_NEAR(p.at(3 * kWidth / 8, 3 * kHeight / 8)[2], kColours[3][2], 10);
  }
}

// Until the feed stops or a minute passes.
double feedUntilStopped(VideoFeed& feed) {
  const auto end = Clock::now() + 60s;
  return feedWhile(feed, [&] { return feed.status().error().empty() && Clock::now() < end; });
}

// The feed calls a receiver that listens (ffplay srt://...?mode=listener); when the receiver goes
// away, the feed stops with one line saying so, never waiting.
TEST(VideoFeed, CallsAnSrtReceiverThatListensAndStopsWhenItLeaves) {
  if (!ffmpegCanSend("srt")) GTEST_SKIP() << "this FFmpeg's libavformat has no SRT";
  const int port = freeUdpPort();
  const std::string url = "srt://127.0.0.1:" + std::to_string(port);
  auto receiver = std::make_unique<FeedReceiver>(url + "?mode=listener", 5);
  ASSERT_TRUE(testing::waitForUdpPort(port, 30s)) << "the receiver never listened on " << url;
  VideoFeed feed(parseFeedUrl(url), kWidth, kHeight, 25);
  double longest_ms = feedUntilReceived(feed, *receiver);
  const std::vector<DecodedPicture> pictures = receiver->wait();
  ASSERT_EQ(pictures.size(), 5u) << receiver->error() << "; " << feed.status().error();
  expectTheQuadrants(pictures);
  EXPECT_EQ(feed.connections(), 1);
  receiver.reset();  // it hangs up
  longest_ms = std::max(longest_ms, feedUntilStopped(feed));
  const std::string error = feed.status().error();
  EXPECT_NE(error.find("feed to " + url + " stopped: "), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_FALSE(feed.offer(kWidth, kHeight, quadrants()));
  EXPECT_LT(longest_ms, 250);
}

// OBS's way: the studio listens, the receiver calls it; when it leaves, the next may call.
TEST(VideoFeed, ListensForAnSrtReceiverThatCallsAndForTheNextWhenItLeaves) {
  if (!ffmpegCanSend("srt")) GTEST_SKIP() << "this FFmpeg's libavformat has no SRT";
  const int port = freeUdpPort();
  const std::string url = "srt://127.0.0.1:" + std::to_string(port);
  VideoFeed feed(parseFeedUrl(url + "?mode=listener"), kWidth, kHeight, 25);
  ASSERT_TRUE(testing::waitForUdpPort(port, 30s)) << "the feed never listened on " << url;
  // Nobody has called yet: pictures offered are dropped, never waited on.
  const std::vector<uint8_t> picture = quadrants();
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(feed.offer(kWidth, kHeight, picture));
  EXPECT_FALSE(feed.connected());
  EXPECT_GE(feed.framesDropped(), 2);
  for (int receivers = 1; receivers <= 2; ++receivers) {
    std::vector<DecodedPicture> pictures;
    // The second calls once the feed has seen the first leave; a call that comes while the feed
    // opens its port again is retried, as a user would.
    for (int attempt = 0; attempt < 3 && pictures.size() < 5; ++attempt) {
      FeedReceiver receiver(url, 5, 30s);
      feedUntilReceived(feed, receiver);
      pictures = receiver.wait();
    }
    ASSERT_EQ(pictures.size(), 5u) << "receiver " << receivers << "; " << feed.status().error();
    expectTheQuadrants(pictures);
    EXPECT_EQ(feed.connections(), receivers);
    const auto end = Clock::now() + 60s;
    while (feed.connected() && Clock::now() < end) {
      feed.offer(kWidth, kHeight, picture);
      std::this_thread::sleep_for(40ms);
    }
    EXPECT_EQ(feed.status().error(), "");
  }
}

// UDP is sent whether anyone listens or not: nothing fails, nothing waits.
TEST(VideoFeed, SendsOverUdpToAPortNobodyListensOnWithoutWaiting) {
  const std::string url = "udp://127.0.0.1:" + std::to_string(freeUdpPort());
  VideoFeed feed(parseFeedUrl(url), kWidth, kHeight, 25);
  const std::vector<uint8_t> picture = quadrants();
  const auto end = Clock::now() + 60s;
  while (feed.framesSent() < 10 && Clock::now() < end) {
    feed.offer(kWidth, kHeight, picture);
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_GE(feed.framesSent(), 10);
  EXPECT_EQ(feed.status().error(), "");
  const auto before = Clock::now();
  feed.close();
  EXPECT_LT(Clock::now() - before, 2s);
}

// An SRT caller whose receiver is not there: the feed stops with one line saying why, while
// offer() never waits; closing it while it calls returns at once.
TEST(VideoFeed, AnSrtCallToAClosedPortFailsCleanlyWithoutWaiting) {
  if (!ffmpegCanSend("srt")) GTEST_SKIP() << "this FFmpeg's libavformat has no SRT";
  const std::string url = "srt://127.0.0.1:" + std::to_string(freeUdpPort());
  {
    VideoFeed feed(parseFeedUrl(url), kWidth, kHeight, 25);
    feed.offer(kWidth, kHeight, quadrants());
    std::this_thread::sleep_for(200ms);
    const auto before = Clock::now();
    feed.close();
    EXPECT_LT(Clock::now() - before, 2s) << "closing waited on the call";
    EXPECT_EQ(feed.status().error(), "");
  }
  VideoFeed feed(parseFeedUrl(url), kWidth, kHeight, 25);
  const double longest_ms = feedUntilStopped(feed);
  const std::string error = feed.status().error();
  EXPECT_NE(error.find("feed to " + url + " stopped: "), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_EQ(feed.framesSent(), 0);
  EXPECT_GT(feed.framesDropped(), 0);
  EXPECT_FALSE(feed.offer(kWidth, kHeight, quadrants()));
  EXPECT_LT(longest_ms, 250);
}

}  // namespace
}  // namespace lumistage
