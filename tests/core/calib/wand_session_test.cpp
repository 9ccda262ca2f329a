#include "core/calib/wand_session.h"

#include <gtest/gtest.h>

#include "core/calib/wand_simulation.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(WandSession, SavesAndLoadsBack) {
  WandSimulationOptions sim;
  sim.samples = 40;
  sim.wand_length_m = 0.4;
  const SimulatedWandSession s = simulateWandSession(makeRingRig(RingRigSpec{}), sim);
  const std::filesystem::path file = testing::testFolder("wand") / "points.txt";
  saveWandSession(s.session, file);
  const WandSession back = loadWandSession(file);
  ASSERT_EQ(back.cameraCount(), s.session.cameraCount());
  ASSERT_EQ(back.sampleCount(), s.session.sampleCount());
  EXPECT_EQ(back.wand_pairs, s.session.wand_pairs);
  ASSERT_EQ(back.floor_marks.size(), 3u);
  EXPECT_EQ(back.floor_marks[1].world_m, Eigen::Vector3d(1, 0, 0));
  for (int sp = 0; sp < back.sampleCount(); ++sp) {
    for (int c = 0; c < back.cameraCount(); ++c) {
      ASSERT_EQ(back.has(sp, c), s.session.has(sp, c));
      if (back.has(sp, c)) {
        EXPECT_LT((back.pixel(sp, c) - s.session.pixel(sp, c)).norm(), 1e-4);
      }
    }
  }
}

// A real wand recording's centroid of a blob the image's edge cut lies a fraction of a pixel off
// the image: that point is left out (with a warning), the rest is read.
TEST(WandSession, APointJustOffTheImageIsLeftOut) {
  const WandSession s = parseWandSession(
      "# lumistage wand points 1\ncamera cam01 640 480\npoint 0 cam01 10 -0.59\n"
      "point 1 cam01 639.7 20\npoint 2 cam01 320 240\n",
      "w.txt");
  EXPECT_EQ(s.sampleCount(), 3);
  EXPECT_FALSE(s.has(0, 0));
  EXPECT_FALSE(s.has(1, 0));
  EXPECT_TRUE(s.has(2, 0));
}

TEST(WandSession, ErrorsNameTheLine) {
  const std::string head = "# lumistage wand points 1\ncamera cam01 640 480\n";
  auto error = [](const std::string& text) {
    return testing::errorOf([&] { parseWandSession(text, "w.txt"); });
  };
  EXPECT_NE(error(head + "point 0 cam02 1 2\n").find("w.txt:3"), std::string::npos);
  EXPECT_NE(error(head + "point 0 cam02 1 2\n").find("unknown camera 'cam02'"), std::string::npos);
  EXPECT_NE(error(head + "point 0 cam01 700 2\n").find("outside camera cam01's 640x480"),
            std::string::npos);
  EXPECT_NE(error(head + "point 0 cam01 5 -1.6\n").find("outside camera cam01's 640x480"),
            std::string::npos);
  EXPECT_NE(error(head + "point x cam01 1 2\n").find("sample: expected a non-negative integer"),
            std::string::npos);
  EXPECT_NE(error("camera cam01 640 480\n").find("w.txt:1"), std::string::npos);
  // A sample id whose room (every camera's, every sample up to it) no machine has.
  EXPECT_NE(error(head + "point 2147483647 cam01 1 1\n").find("sample 2147483647 is beyond"),
            std::string::npos);
  EXPECT_NE(error(head + "pair 0 1000000\n").find("w.txt:3: sample 1000000 is beyond"),
            std::string::npos);
  EXPECT_NE(error(head + "floor 2147483647 0 1 0\n").find("w.txt:3: sample 2147483647 is beyond"),
            std::string::npos);
  EXPECT_NE(error(head + "blob 1\n").find("unknown line kind 'blob'"), std::string::npos);
  // A later version of the format may mean something else by the same lines.
  EXPECT_NE(error("# lumistage wand points 2\ncamera cam01 640 480\n")
                .find("w.txt:1: wand points version ' 2': this build reads version 1"),
            std::string::npos);
  // What is echoed from the file is quoted: a terminal escape comes back as \x1b, a long word cut.
  const std::string escaped = error(head + "point 0 cam01 1 \x1b[2J\n");
  EXPECT_NE(escaped.find("found '\\x1b[2J'"), std::string::npos) << escaped;
  EXPECT_EQ(escaped.find('\x1b'), std::string::npos) << escaped;
  const std::string huge = error(head + std::string(100000, 'z') + " 1\n");
  EXPECT_NE(huge.find("(100000 bytes in all)"), std::string::npos);
  EXPECT_LT(huge.size(), 400u);
  const WandSession ok = parseWandSession(head + "point 3 cam01 10.5 20.25\n", "w.txt");
  EXPECT_EQ(ok.sampleCount(), 4);
  EXPECT_TRUE(ok.has(3, 0));
  EXPECT_FALSE(ok.has(2, 0));
}

}  // namespace
}  // namespace lumistage
