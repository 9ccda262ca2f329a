// The studio coordinator's frames: which frame ids it follows, what it refuses, drops, overtakes
// or holds back, and its deadlines, with two nodes played by the test.
#include <gtest/gtest.h>

#include <thread>

#include "core/pipeline/studio_coordinator.h"
#include "tests/core/pipeline/scripted_studio.h"

namespace lumistage {
namespace {

using namespace lumistage::testing;
using std::chrono::milliseconds;

// One node's silhouettes of a frame a trillion frames ahead (a corrupt or hostile message) are
// refused and counted; they neither end the frames in flight nor leave every later frame "done".
TEST(StudioCoordinator, SilhouettesOfAFrameFarFromTheOthersAreRefusedAndFramesGoOn) {
  TwoNodeStudio two(milliseconds(50));
  ASSERT_TRUE(two.node1.send(1'000'000'000'000, SilhouettesData{}));
  two.studio.runFor(milliseconds(300));  // past every deadline
  EXPECT_EQ(badMessagesOf(two.studio, "node1"), 1);
  ASSERT_TRUE(two.both(2));
  EXPECT_EQ(nextPoseFrame(two.node1, two.studio, 2), 2);
  EXPECT_EQ(badMessagesOf(two.studio, "node2"), 0);
}

// A node's masks of a camera that is not its own (a node started with another rig file), or of
// one of its cameras twice, are refused and counted: they carved the hull, the last one to arrive
// winning.
TEST(StudioCoordinator, MasksOfAnotherNodesCameraOrTwiceOfOneAreRefused) {
  TwoNodeStudio two(milliseconds(50));
  const int step = StudioCoordinatorOptions{}.silhouette_step, w = 160 / step, h = 120 / step;
  const auto mask = [&](int camera) {
    return SilhouetteMaskData{camera, w, h, std::vector<uint8_t>(size_t(w * h + 7) / 8, 0), {}};
  };
  ASSERT_TRUE(two.node1.send(2, SilhouettesData{{mask(0), mask(1), mask(0)}}));
  ASSERT_TRUE(two.node2.send(2, SilhouettesData{{mask(1)}}));
  EXPECT_EQ(nextPoseFrame(two.node1, two.studio, 2), 2);
  EXPECT_EQ(badMessagesOf(two.studio, "node1"), 2);
  EXPECT_EQ(badMessagesOf(two.studio, "node2"), 0);
}

// The silhouettes each node keyed for a frame are kept with it once fitted, as sent, for the
// technician's overlay (whatever the nodes key on); a frame never fitted has none.
TEST(StudioCoordinator, TheSilhouettesOfAFittedFrameAreKeptForTheOverlay) {
  TwoNodeStudio two(milliseconds(50));
  const int step = StudioCoordinatorOptions{}.silhouette_step, w = 160 / step, h = 120 / step;
  const auto mask = [&](int camera, int cell) {
    SilhouetteMaskData m{camera, w, h, std::vector<uint8_t>(size_t(w * h + 7) / 8, 0), {}};
    m.bits[size_t(cell) / 8] |= uint8_t(1u << (cell % 8));
    return m;
  };
  ASSERT_TRUE(two.node1.send(3, SilhouettesData{{mask(0, 7 * w + 5)}}));
  ASSERT_TRUE(two.node2.send(3, SilhouettesData{{mask(1, 20 * w + 30)}}));
  ASSERT_EQ(nextPoseFrame(two.node1, two.studio, 3), 3);
  const std::vector<LowResSilhouette>* kept = two.studio.silhouettesOf(3);
  ASSERT_NE(kept, nullptr);
  ASSERT_EQ(kept->size(), 2u);
  for (const LowResSilhouette& s : *kept) {
    ASSERT_TRUE(s.camera == 0 || s.camera == 1);
    ASSERT_EQ(s.width, w);
    EXPECT_EQ(s.at(5, 7), s.camera == 0);
    EXPECT_EQ(s.at(30, 20), s.camera == 1);
  }
  EXPECT_EQ(two.studio.silhouettesOf(4), nullptr);
}

// Frame 10 waits for a late node while frame 11 comes whole and begins: at 10's deadline it is
// dropped, not fitted after 11 (the tracker's prediction run backwards, or 11 pushed out of its
// queue).
TEST(StudioCoordinator, AFrameLateAfterANewerOneBeganIsDropped) {
  TwoNodeStudio two(milliseconds(300));
  ASSERT_TRUE(two.node1.send(10, SilhouettesData{}));
  ASSERT_TRUE(two.both(11));
  std::vector<int64_t> posed;
  for (int k = 0; k < 2; ++k) {  // up to 3 s after 11: well past frame 10's deadline
    const std::optional<Message> pose = two.node1.await<PoseData>(two.studio);
    if (pose) posed.push_back(pose->frame_id);
  }
  EXPECT_NE(std::find(posed.begin(), posed.end(), 11), posed.end());
  EXPECT_EQ(std::find(posed.begin(), posed.end(), 10), posed.end()) << "frame 10 posed after 11";
  EXPECT_EQ(two.studio.report().frames_refused, 1);  // counted as dropped at admission
}

// A frame still waiting for the node's statistics when a newer frame is shown will never be: it
// is dropped as overtaken (the drops' causes add up, and `lumistage run` says them).
TEST(StudioCoordinator, AFrameStillOpenWhenANewerOneIsShownIsOvertaken) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(5000);  // frame 1 does not reach its deadline in this test
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  ASSERT_TRUE(node.send(1, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));  // and no statistics for it
  ASSERT_TRUE(node.send(2, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  RefinementStatistics stats;
  stats.reset(10, options.refine.offset_count, options.refine.colour_bits);
  ASSERT_TRUE(node.send(2, statisticsMessage(stats, options.refine)));
  ASSERT_TRUE(node.await<OffsetsData>(studio));
  ASSERT_TRUE(node.send(2, onePixelImage(studio.view(), 200)));
  EXPECT_EQ(framesDoneAfter(studio, 1, 300), 1);
  const RunReport r = studio.report();
  EXPECT_EQ(r.frames_dropped, 1);
  EXPECT_EQ(r.frames_overtaken, 1);
  EXPECT_EQ(r.frames_refused + r.frames_unshown, 0);
}

// A node that is heard (heartbeats) but sends no silhouettes (its cameras unplugged) while the
// other's come holds no frame once lost_after has passed: the frames' poses go out without waiting
// for its silhouettes (the deadline is 5 s, the wait for a pose 3 s) and are not sent to it, whose
// statistics would never come. Every frame waited out two deadlines before.
TEST(StudioCoordinator, ANodeHeardWithoutSilhouettesHoldsNoFrame) {
  TwoNodeStudio two(milliseconds(5000));
  for (int k = 0; k < 15; ++k) {  // 1.5 s of node1's frames, node2's heartbeats only
    ASSERT_TRUE(two.node1.send(2 + k, SilhouettesData{}));
    ASSERT_TRUE(two.node2.send(0, HeartbeatData{}));
    two.studio.runFor(milliseconds(100));
  }
  // The frames after the first second were posed at once (three in flight: 12 to 14), node2's
  // silhouettes not awaited, and node2 was sent none of their poses.
  const std::optional<int64_t> posed = nextPoseFrame(two.node1, two.studio, 2);
  ASSERT_TRUE(posed);
  EXPECT_GE(*posed, 11);
  EXPECT_EQ(nextPoseFrame(two.node2, two.studio, 2), std::nullopt);
  EXPECT_EQ(two.studio.report().nodes.size(), 2u);
}

// Two nodes heard for 1.5 s before any camera delivers (cameras slow to open): the first frame
// waits for both nodes' silhouettes, instead of beginning with the first node's cameras alone (a
// node counted as silent by the clock, not against the others).
TEST(StudioCoordinator, NodesWhoseCamerasAreSlowToStartAreAllAwaited) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(5000);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node1(studio.endpoint(), "node1"), node2(studio.endpoint(), "node2");
  for (int k = 0; k < 15; ++k) {
    ASSERT_TRUE(node1.send(0, HeartbeatData{}));
    ASSERT_TRUE(node2.send(0, HeartbeatData{}));
    studio.runFor(milliseconds(100));
  }
  ASSERT_TRUE(node1.send(1, SilhouettesData{}));
  for (int k = 0; k < 10; ++k) {  // a second, both heard
    ASSERT_TRUE(node1.send(0, HeartbeatData{}));
    ASSERT_TRUE(node2.send(0, HeartbeatData{}));
    EXPECT_FALSE(node1.await<PoseData>(studio, 10)) << "posed without node2's silhouettes";
  }
  ASSERT_TRUE(node2.send(1, SilhouettesData{}));
  EXPECT_TRUE(node1.await<PoseData>(studio));
}

// Two nodes, one heard but without silhouettes; the other's cameras restart (frame ids near 0):
// the studio follows it, instead of waiting forever for a majority the silent node never joins.
TEST(StudioCoordinator, ANodeWithoutSilhouettesDoesNotVoteOnTheFrameIds) {
  TwoNodeStudio two(milliseconds(50), 5000);
  for (int k = 0; k < 15; ++k) {
    ASSERT_TRUE(two.node2.send(0, HeartbeatData{}));
    ASSERT_TRUE(two.node1.send(5001 + k, SilhouettesData{}));
    two.studio.runFor(milliseconds(100));
  }
  ASSERT_TRUE(two.node1.send(3, SilhouettesData{}));
  bool posed = false;
  for (int k = 0; k < 20 && !posed; ++k) {  // past the poses of the frames before
    const std::optional<Message> pose = two.node1.await<PoseData>(two.studio);
    if (!pose) break;
    posed = pose->frame_id == 3;
  }
  EXPECT_TRUE(posed) << "no pose for frame 3 after the cameras restarted";
}

// When most nodes' frame ids move together (the cameras restarted, or the session), forward or
// back, the studio follows them; a node alone is not followed.
TEST(StudioCoordinator, WhenMostNodesFrameIdsMoveTogetherTheStudioFollows) {
  TwoNodeStudio two(milliseconds(50), 5000);
  for (const int64_t moved : {900000, 3}) {
    SCOPED_TRACE(moved);
    ASSERT_TRUE(two.node1.send(moved, SilhouettesData{}));  // alone: refused
    two.studio.runFor(milliseconds(100));
    ASSERT_TRUE(two.node1.send(moved + 1, SilhouettesData{}));  // still alone: refused
    two.studio.runFor(milliseconds(100));
    ASSERT_TRUE(two.node2.send(moved + 1, SilhouettesData{}));  // now both: followed
    EXPECT_EQ(nextPoseFrame(two.node1, two.studio, moved), moved + 1);
    ASSERT_TRUE(two.both(moved + 2));
    EXPECT_EQ(nextPoseFrame(two.node1, two.studio, moved + 2), moved + 2);
  }
  EXPECT_EQ(badMessagesOf(two.studio, "node1"), 4);  // both its messages before node2's moved
  EXPECT_EQ(badMessagesOf(two.studio, "node2"), 0);
}

// A node's cameras restart alone (its PC rebooted, its cameras power-cycled): its silhouettes,
// arriving in step with the other node's but counted from 1 again, are refused; after a second it
// is told the shift that puts its ids on the other's count, and shifted they are taken again.
TEST(StudioCoordinator, ANodeWhoseCamerasRestartedAloneIsToldToFollowTheOthers) {
  TwoNodeStudio two(milliseconds(200), 500);
  for (int64_t f = 501; f < 541; ++f) {  // 40 frames together, about 30 a second
    ASSERT_TRUE(two.both(f));
    two.studio.runFor(milliseconds(30));
  }
  std::optional<Message> told;
  int64_t f = 541;
  const auto restarted = std::chrono::steady_clock::now();
  for (; f < 700 && !told; ++f) {
    ASSERT_TRUE(two.node1.send(f, SilhouettesData{}));
    ASSERT_TRUE(two.node2.send(f - 540, SilhouettesData{}));
    told = two.node2.await<FrameIdsData>(two.studio, 3);
  }
  ASSERT_TRUE(told) << "node2 was never told how its ids lie";
  EXPECT_EQ(std::get<FrameIdsData>(told->body).offset, 540);
  EXPECT_GE(std::chrono::steady_clock::now() - restarted, std::chrono::seconds(1))
      << "told before a second of refusals";
  const int64_t refused = badMessagesOf(two.studio, "node2");
  for (int k = 1; k <= 10; ++k) {
    ASSERT_TRUE(two.both(f + k));
    two.studio.runFor(milliseconds(30));
  }
  EXPECT_EQ(badMessagesOf(two.studio, "node2"), refused);
  // Its silhouettes used again, the frames wait for it and it is sent their poses: one of the
  // frames from f + 1 on, while both nodes go on sending, as nodes do. (Waiting on the ten frames
  // above alone, one run of the whole suite on the 2-core machine saw no pose reach node2 within
  // 3 s, 2026-12-04; the other runs did.)
  bool posed = false;
  for (int k = 11; k <= 40 && !posed; ++k) {
    posed = nextPoseFrame(two.node2, two.studio, f + 1).has_value();
    if (!posed) {
      ASSERT_TRUE(two.both(f + k));
    }
  }
  EXPECT_TRUE(posed);
}

// The first statistics of a frame set the sums' sizes. When they are refused (here another mesh's,
// their body corrupted), the next node's set them afresh instead of being refused in turn; and a
// node's image sent twice is blended once.
TEST(StudioCoordinator, OneNodesBadStatisticsOrRepeatedImageSpoilNoOtherNodes) {
  TwoNodeStudio two(milliseconds(2000));
  StudioCoordinator& studio = two.studio;
  ScriptedNode &node1 = two.node1, &node2 = two.node2;
  const RefineConfig refine;
  RefinementStatistics stats;
  stats.reset(10, refine.offset_count, refine.colour_bits);
  RefinementStatistics other;
  other.reset(11, refine.offset_count, refine.colour_bits);
  VertexStatisticsData broken = statisticsMessage(other, refine);
  for (size_t i = 8; i < broken.packed.size(); ++i) broken.packed[i] ^= 0x5a;
  ASSERT_TRUE(node1.send(1, broken));
  studio.runFor(milliseconds(50));
  ASSERT_TRUE(node1.send(1, statisticsMessage(stats, refine)));
  ASSERT_TRUE(node2.send(1, statisticsMessage(stats, refine)));
  ASSERT_TRUE(node1.await<OffsetsData>(studio));
  EXPECT_GE(badMessagesOf(studio, "node1"), 1);
  EXPECT_EQ(badMessagesOf(studio, "node2"), 0);

  const ViewData& view = studio.view();
  const auto image = [&](uint8_t red, uint8_t alpha) {
    PartialImageData i{view.view, view.width, view.height, ImageEncoding::kRawRgba,
                       std::vector<uint8_t>(size_t(view.width) * view.height * 4, 0)};
    i.data[0] = red, i.data[3] = alpha;
    return i;
  };
  ASSERT_TRUE(node1.send(1, image(200, 255)));
  ASSERT_TRUE(node1.send(1, image(0, 255)));  // the same node and view again
  studio.runFor(milliseconds(50));
  ASSERT_TRUE(node2.send(1, image(0, 0)));
  for (int slice = 0; slice < 300 && studio.framesDone() == 0; ++slice)
    studio.runFor(milliseconds(10));
  ASSERT_EQ(studio.framesDone(), 1);
  EXPECT_EQ(studio.lastImage(0).rgba.at(0), 200);
}

// A frame without one node's image (it missed the deadline) lacks what only that node's cameras
// saw: while whole frames come it is held back, not shown; when none has come for hold_incomplete,
// it is shown rather than leave the view frozen. (Every frame with any image was shown: under
// load the director's view was full of holes.)
TEST(StudioCoordinator, AFrameWithoutANodesImageIsHeldBackWhileWholeOnesCome) {
  TwoNodeStudio two(milliseconds(100));
  StudioCoordinator& studio = two.studio;
  // Frame f through every stage, its image from node1 and, when `whole`, from node2.
  const auto frame = [&](int64_t f, bool whole) {
    ASSERT_TRUE(two.posed(f));
    ASSERT_TRUE(two.node1.send(f, two.statistics));
    ASSERT_TRUE(two.node2.send(f, two.statistics));
    ASSERT_TRUE(two.node1.await<OffsetsData>(studio));
    ASSERT_TRUE(two.node1.send(f, onePixelImage(studio.view(), uint8_t(10 * f))));
    if (whole) {
      ASSERT_TRUE(two.node2.send(f, onePixelImage(studio.view(), uint8_t(10 * f))));
    }
  };
  frame(1, true);
  ASSERT_EQ(framesDoneAfter(studio, 1, 300), 1);
  const auto shown = std::chrono::steady_clock::now();
  frame(2, false);
  studio.runFor(milliseconds(300));  // past its images' deadline
  ASSERT_LT(std::chrono::steady_clock::now() - shown, StudioCoordinatorOptions{}.hold_incomplete)
      << "too slow a machine for this test";
  EXPECT_EQ(studio.framesDone(), 1);
  EXPECT_EQ(studio.report().frames_held, 1);
  EXPECT_EQ(studio.lastImage(0).rgba.at(0), 10);
  studio.runFor(StudioCoordinatorOptions{}.hold_incomplete);
  frame(3, false);
  EXPECT_EQ(framesDoneAfter(studio, 2, 300), 2);
  EXPECT_EQ(studio.report().frames_incomplete, 1);
  EXPECT_EQ(studio.lastImage(0).rgba.at(0), 30);
}

// A node whose statistics come 200 ms after the pose, past the 100 ms deadline (an overloaded
// node): every frame is drawn without its cameras (node1's image alone), its late answers are
// timed, the statistics' deadline stretches to take them, and after a few frames its statistics
// are used and its image asked for. (With a fixed deadline every frame went without it.) The
// deadline stays stretched while the node is late, though the frames are whole again: it went
// back after ten frames, and the node missed again.
TEST(StudioCoordinator, TheDeadlinesStretchToANodeThatAnswersLate) {
  TwoNodeStudio two(milliseconds(100));
  StudioCoordinator& studio = two.studio;
  int64_t first_with_node2 = -1;
  std::vector<int64_t> without_node2_after;
  EXPECT_EQ(studio.report().statistics_deadline_ms, 100.0);
  EXPECT_FALSE(studio.report().deadlines_following);
  for (int64_t f = 1;; ++f) {
    if (first_with_node2 < 0 ? f > 16 : f > first_with_node2 + 12) break;
    ASSERT_TRUE(two.posed(f));
    ASSERT_TRUE(two.node1.send(f, two.statistics));
    ASSERT_TRUE(two.node1.send(f, onePixelImage(studio.view(), 100)));
    studio.runFor(milliseconds(200));
    ASSERT_TRUE(two.node2.send(f, two.statistics));
    // node2 is sent the frame's offsets only when its statistics made the deadline.
    const std::optional<Message> offsets = two.node2.await<OffsetsData>(studio, 40);
    const bool used = offsets && offsets->frame_id == f;
    if (used && first_with_node2 < 0) first_with_node2 = f;
    if (!used && first_with_node2 > 0) without_node2_after.push_back(f);
    if (used) {
      ASSERT_TRUE(two.node2.send(f, onePixelImage(studio.view(), 100)));
    }
    studio.runFor(milliseconds(300));  // the frame done or given up
  }
  EXPECT_GT(first_with_node2, 1) << "the late node's statistics were used from the start";
  ASSERT_NE(first_with_node2, -1) << "the late node's statistics were never used";
  EXPECT_EQ(without_node2_after, std::vector<int64_t>{})
      << "the deadline went back while the node was still late";
  // The report says so: the statistics' deadline past node2's 200 ms, the images' (node1's and
  // node2's, at once) the base.
  const RunReport report = studio.report();
  EXPECT_TRUE(report.deadlines_following);
  EXPECT_GT(report.statistics_deadline_ms, 200.0);
  EXPECT_LE(report.statistics_deadline_ms, 480.0);
  EXPECT_EQ(report.image_deadline_ms, 100.0);
}

}  // namespace
}  // namespace lumistage
