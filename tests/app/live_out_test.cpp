// The live feeds out of `lumistage run`, received as other programs receive them: real processes,
// a real OSC server and a real FFmpeg video receiver on 127.0.0.1.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include "tests/app/shell_command.h"
#include "tests/feed_receiver.h"
#include "tests/osc_receiver.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using testing::OscBundle;
using testing::OscReceiver;

const std::string kCli = LUMISTAGE_CLI;

using testing::Result;
using testing::run;

// folder/session: a synthetic take of the virtual studio, 4 cameras on 2 nodes.
::testing::AssertionResult synthSession(const fs::path& folder) {
  Result r =
      run(kCli + " rig ring --cameras 4 --width 320 --height 240 --cameras-per-node 2 --out " +
          (folder / "rig.yaml").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  std::ofstream(folder / "studio.yaml")
      << "format: lumistage-studio\nversion: 1\nrig: rig.yaml\nactor:\n  vertices: 2000\n";
  r = run(kCli + " synth --config " + (folder / "studio.yaml").string() +
          " --frames 6 --bayer --out " + (folder / "session").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  return ::testing::AssertionSuccess();
}

TEST(LiveOut, RunStreamsTheSkeletonOfEveryFrameShownOverOsc) {
  const fs::path folder = testing::testFolder("live_out");
  ASSERT_TRUE(synthSession(folder));
  OscReceiver receiver;
  ASSERT_GT(receiver.port(), 0);
  const std::string target = "127.0.0.1:" + std::to_string(receiver.port());
  const Result r = run(kCli + " run --session " + (folder / "session").string() +
                       " --frames 12 --seconds 60 --osc " + target);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("streaming the skeleton to " + target), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("12 frames in all"), std::string::npos) << r.output;
  std::smatch said;
  const std::regex sent_re("skeleton to " + std::regex_replace(target, std::regex("\\."), "\\.") +
                           ": ([0-9]+) bundles sent, ([0-9]+) lost");
  ASSERT_TRUE(std::regex_search(r.output, said, sent_re)) << r.output;
  const size_t sent = std::stoul(said[1]);
  EXPECT_EQ(said[2], "0");
  // A bundle for every frame shown: the 12 counted, and any shown before the figures began to
  // count or while the run ended.
  EXPECT_GE(sent, 12u);
  const std::vector<OscBundle> bundles = receiver.waitForBundles(sent);
  EXPECT_EQ(bundles.size(), sent);
  EXPECT_EQ(receiver.loose(), 0u);
  int tracked = 0;
  for (const OscBundle& bundle : bundles) {
    ASSERT_EQ(bundle.size(), 25u);
    EXPECT_EQ(bundle.front().path, "/VMC/Ext/Root/Pos");
    ASSERT_EQ(bundle[1].text(0), "Hips");
    // The actor stands on the stage: hips a metre up (Unity's Y), within the ring of cameras.
    EXPECT_GT(bundle[1].number(2), 0.6f);
    EXPECT_LT(bundle[1].number(2), 1.3f);
    EXPECT_LT(std::abs(bundle[1].number(1)), 3.0f);
    EXPECT_LT(std::abs(bundle[1].number(3)), 3.0f);
    EXPECT_EQ(bundle[23].path, "/VMC/Ext/OK");
    tracked += bundle[23].integer(1) == 3;
  }
  // The tracker finds the synthetic actor (its first frames may be the placed generic human).
  EXPECT_GE(tracked, 6) << bundles.size() << " bundles";
  // The sender's clock in each bundle never goes back: one bundle a frame, in order.
  for (size_t b = 1; b < bundles.size(); ++b)
    EXPECT_GE(bundles[b].back().number(0), bundles[b - 1].back().number(0)) << b;
}

TEST(LiveOut, RunRefusesAnOscTargetThatIsNotHostAndPortBeforeStartingNodes) {
  for (const char* bad : {"localhost", "127.0.0.1:0", "127.0.0.1:99999", ":39539"}) {
    const Result r = run(kCli + " run --session /nonexistent --frames 1 --osc " + bad);
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--osc"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("HOST:PORT"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("starting"), std::string::npos) << r.output;
  }
}

TEST(LiveOut, RunFeedsTheViewOverUdpToAReceiverThatDecodesIt) {
  const fs::path folder = testing::testFolder("live_feed");
  ASSERT_TRUE(synthSession(folder));
  const int port = testing::freeUdpPort();
  const std::string url = "udp://127.0.0.1:" + std::to_string(port);
  // As ffplay udp://127.0.0.1:PORT would: bound before the run starts, it gives up at its
  // deadline should nothing come.
  testing::FeedReceiver receiver(url, 3, std::chrono::seconds(120));
  ASSERT_TRUE(testing::waitForUdpPort(port, std::chrono::seconds(30)));
  const fs::path json = folder / "run.json";
  const Result r = run(kCli + " run --session " + (folder / "session").string() +
                       " --frames 20 --seconds 60 --json " + json.string() + " --feed " + url);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("feeding the view to " + url + " (H.264 in MPEG-TS, 320x240)"),
            std::string::npos)
      << r.output;
  std::smatch said;
  const std::regex sent_re("view fed to udp://127\\.0\\.0\\.1:" + std::to_string(port) +
                           ": ([0-9]+) frames sent, ([0-9]+) dropped");
  ASSERT_TRUE(std::regex_search(r.output, said, sent_re)) << r.output;
  EXPECT_GE(std::stoul(said[1]), 3u) << r.output;
  const std::vector<testing::DecodedPicture> pictures = receiver.wait();
  ASSERT_EQ(pictures.size(), 3u) << receiver.error();
  for (const testing::DecodedPicture& p : pictures) {
    EXPECT_EQ(p.width, 320);
    EXPECT_EQ(p.height, 240);
    // The view: the actor rendered over black, so neither all black nor all one colour.
    const auto [least, most] = std::minmax_element(p.rgb.begin(), p.rgb.end());
    EXPECT_LT(*least, 30);
    EXPECT_GT(*most, 80);
  }
  std::ifstream in(json);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(
      text.find("\"feed\": {\"url\": \"" + url + "\", \"frames_sent\": " + std::string(said[1])),
      std::string::npos)
      << text;
}

TEST(LiveOut, RunRefusesAFeedThatIsNoFeedBeforeStartingNodes) {
  for (const char* bad :
       {"rtmp://127.0.0.1/live", "udp://127.0.0.1", "view.ts", "udp://127.0.0.1:99999"}) {
    const Result r = run(kCli + " run --session /nonexistent --frames 1 --feed " + bad);
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--feed"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("udp://HOST:PORT, srt://HOST:PORT"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("v4l2:///dev/videoN"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("starting"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace lumistage
