// The studio coordinator: a frame's course, its nodes' answers and their times, and what it
// refuses.
#include "core/pipeline/studio_coordinator.h"

#include <gtest/gtest.h>

#include <thread>

#include "tests/core/pipeline/scripted_studio.h"

namespace lumistage {
namespace {

using namespace lumistage::testing;
using std::chrono::milliseconds;

// A frame that no node's image reaches shows nothing: it is dropped, not done, so that a run of N
// frames shows N (while the nodes start, their first frames' statistics never come).
TEST(StudioCoordinator, AFrameNoNodesImageReachedIsDroppedNotDone) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(50);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());

  // Frame 1: silhouettes, a pose back, and then nothing from the node.
  ASSERT_TRUE(node.send(1, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  studio.runFor(milliseconds(300));  // past the statistics' deadline
  EXPECT_EQ(studio.framesDone(), 0);
  EXPECT_EQ(studio.report().frames_dropped, 1);
  EXPECT_EQ(studio.report().frames_unshown, 1);  // dropped for that cause, and no other
  EXPECT_EQ(studio.report().frames_refused, 0);
  EXPECT_EQ(studio.report().frames_overtaken, 0);
  EXPECT_TRUE(studio.lastImage(0).rgba.empty());

  // Frame 2: the node answers every stage, and the frame is done with its image.
  ASSERT_TRUE(node.send(2, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  const StudioCoordinatorOptions defaults;
  RefinementStatistics stats;
  stats.reset(10, defaults.refine.offset_count, defaults.refine.colour_bits);
  ASSERT_TRUE(node.send(2, statisticsMessage(stats, defaults.refine)));
  ASSERT_TRUE(node.await<OffsetsData>(studio));
  ASSERT_TRUE(node.send(2, onePixelImage(studio.view(), 200)));  // one red pixel
  EXPECT_EQ(framesDoneAfter(studio, 1, 300), 1);
  EXPECT_EQ(studio.report().frames_dropped, 1);
  ASSERT_FALSE(studio.lastImage(0).rgba.empty());
  EXPECT_EQ(studio.lastImage(0).rgba[0], 200);
}

// A frame's latency runs from its capture to its image on the wall clock, which the node's PC
// and the studio's keep in step; a node whose clock is days off is not averaged in (its steady
// clock, counted from its own boot, put the latency hours off or below zero).
TEST(StudioCoordinator, LatencyIsMeasuredOnTheWallClockAndOnlyWhenTheClocksAgree) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(2000);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  const StudioCoordinatorOptions defaults;
  RefinementStatistics stats;
  stats.reset(10, defaults.refine.offset_count, defaults.refine.colour_bits);
  const PartialImageData image = onePixelImage(studio.view());
  const int64_t ten_days_ns = int64_t(10) * 24 * 3600 * 1'000'000'000;
  for (int64_t frame = 1; frame <= 2; ++frame) {
    ASSERT_TRUE(node.send(frame, SilhouettesData{}, frame == 1 ? wallNowNs() - ten_days_ns : 0));
    ASSERT_TRUE(node.await<PoseData>(studio));
    ASSERT_TRUE(node.send(frame, statisticsMessage(stats, defaults.refine)));
    ASSERT_TRUE(node.await<OffsetsData>(studio));
    ASSERT_TRUE(node.send(frame, image));
    ASSERT_EQ(framesDoneAfter(studio, frame, 100), frame);
  }
  const RunReport report = studio.report();
  EXPECT_GT(report.latency_ms_p95, 0);
  EXPECT_LT(report.latency_ms_p95, 5000);
}

// The director resizes the view while a frame is refined: the frame's image, drawn at the size sent
// with its pose, is taken and the frame done (it was refused for its size, and the frame dropped).
TEST(StudioCoordinator, AFramesImagesAreTakenByTheViewSentWithItsPose) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(2000);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  ASSERT_TRUE(node.send(1, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  const StudioCoordinatorOptions defaults;
  RefinementStatistics stats;
  stats.reset(10, defaults.refine.offset_count, defaults.refine.colour_bits);
  ASSERT_TRUE(node.send(1, statisticsMessage(stats, defaults.refine)));
  ASSERT_TRUE(node.await<OffsetsData>(studio));
  const ViewData asked = studio.view();
  ViewData resized = asked;
  resized.width /= 2, resized.height /= 2;
  studio.setView(resized);
  ASSERT_TRUE(node.send(1, onePixelImage(asked, 200)));
  EXPECT_EQ(framesDoneAfter(studio, 1, 100), 1);  // 1 s, half the deadline
  ASSERT_FALSE(studio.lastImage(0).rgba.empty());
  EXPECT_EQ(studio.lastImage(0).width, asked.width);
}

// A node that sends silhouettes at another step (an older version: step 8) is counted as sending
// bad messages, its frames still get a pose, and silhouettes of the right size count as before.
// A node the studio hears from for the first time is answered at once (the take under way, none
// here), nobody being on stage yet: its word that it reached the studio, which it logs.
TEST(StudioCoordinator, ANodeHeardForTheFirstTimeIsAnswered) {
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, {});
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  ASSERT_TRUE(node.send(-1, HeartbeatData{}));
  const std::optional<Message> answer = node.await<RecordData>(studio);
  ASSERT_TRUE(answer);
  EXPECT_TRUE(std::get<RecordData>(answer->body).take.empty());
}

TEST(StudioCoordinator, SilhouettesOfAnotherStepAreRefusedAndCounted) {
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, {});
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  const auto mask = [](int step) {
    const int w = 160 / step, h = 120 / step;
    return SilhouetteMaskData{0, w, h, std::vector<uint8_t>(size_t(w * h + 7) / 8, 0), {}};
  };
  const auto badMessages = [&] {
    for (const NodeReport& n : studio.report().nodes)
      if (n.name == "node1") return n.bad_messages;
    return int64_t(-1);
  };
  ASSERT_TRUE(node.send(1, SilhouettesData{{mask(8)}}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  EXPECT_EQ(badMessages(), 1);
  ASSERT_TRUE(node.send(2, SilhouettesData{{mask(StudioCoordinatorOptions{}.silhouette_step)}}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  EXPECT_EQ(badMessages(), 1);
}

// With the offsets, the studio sends which cameras see each vertex of the body the nodes pose
// and refine: what each node's renderer would compute from the same pose and offsets.
TEST(StudioCoordinator, OffsetsComeWithTheRefinedBodysVisibility) {
  StudioCoordinatorOptions options;
  options.body = std::make_shared<const SkinnedMesh>(loadGenericHuman());
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  const int vertices = options.body->rest.vertexCount();
  const RefineConfig& refine = options.refine;
  for (const int frame : {1, 2}) {
    ASSERT_TRUE(node.send(frame, SilhouettesData{}));
    const std::optional<Message> pose = node.await<PoseData>(studio);
    ASSERT_TRUE(pose);
    // Frame 1: statistics of the body's vertices; frame 2: of another mesh, refused (they set the
    // sums' sizes, and the other nodes' statistics of the body were refused in turn).
    const int n = frame == 1 ? vertices : 10;
    RefinementStatistics stats;
    stats.reset(n, refine.offset_count, refine.colour_bits);
    // Every vertex outside a silhouette from the posed surface out: the refinement moves it in.
    for (int v = 0; v < n; ++v)
      for (int t = refine.zeroOffsetIndex(); t < refine.offset_count; ++t)
        stats.outside[size_t(v) * refine.offset_count + t] = 1;
    ASSERT_TRUE(node.send(frame, statisticsMessage(stats, refine)));
    const std::optional<Message> offsets = node.await<OffsetsData>(studio);
    if (frame == 2) {
      EXPECT_FALSE(offsets);
      EXPECT_EQ(badMessagesOf(studio, "node1"), 1);
      continue;
    }
    ASSERT_TRUE(offsets);
    const OffsetsData& sent = std::get<OffsetsData>(offsets->body);
    const int unmoved = refine.zeroLevel();
    ASSERT_TRUE(std::all_of(sent.offsets.begin(), sent.offsets.end(),
                            [&](uint8_t level) { return level < unmoved; }));
    Pose posed;
    std::vector<Eigen::Affine3f> transforms;
    Eigen::Matrix3Xf positions, normals, refined;
    posedBodyMesh(*options.body, std::get<PoseData>(pose->body), posed, transforms, positions,
                  normals);
    applyOffsets(refine, sent.offsets, positions, normals, refined);
    VertexVisibility expected;
    const LumigraphParams lumigraph;
    expected.compute(studio.rig(), refined, options.body->rest.triangles,
                     lumigraph.depth_map_divisor, lumigraph.depth_tolerance_m);
    ASSERT_EQ(sent.visibility.size(), size_t(vertices));
    EXPECT_TRUE(
        std::equal(sent.visibility.begin(), sent.visibility.end(), expected.masks().begin()));
    const auto seen = std::count_if(sent.visibility.begin(), sent.visibility.end(),
                                    [](uint16_t m) { return m != 0; });
    EXPECT_GT(seen, vertices / 4) << "the body stands in the cameras' view";
    EXPECT_LT(seen, vertices) << "and hides its far side";
  }
}

// How long a node takes to answer is measured on the studio's clock: from the pose to its
// statistics, from the offsets to its image.
TEST(StudioCoordinator, ANodesAnswerTimesAreMeasured) {
  StudioCoordinatorOptions options;
  options.deadline = milliseconds(2000);  // the node's slowness is not a miss
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(2, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint());
  ASSERT_EQ(studio.report().nodes.at(0).statistics_ms, -1);  // nothing answered yet
  ASSERT_TRUE(node.send(1, SilhouettesData{}));
  ASSERT_TRUE(node.await<PoseData>(studio));
  std::this_thread::sleep_for(milliseconds(150));  // the node at work on its statistics
  const RefineConfig& refine = options.refine;
  RefinementStatistics stats;
  stats.reset(10, refine.offset_count, refine.colour_bits);
  ASSERT_TRUE(node.send(1, statisticsMessage(stats, refine)));
  ASSERT_TRUE(node.await<OffsetsData>(studio));
  std::this_thread::sleep_for(milliseconds(80));  // rendering
  ASSERT_TRUE(node.send(1, onePixelImage(studio.view())));
  ASSERT_EQ(framesDoneAfter(studio, 1, 300), 1);
  const NodeReport report = studio.report().nodes.at(0);
  EXPECT_GE(report.statistics_ms, 150);
  EXPECT_LT(report.statistics_ms, 1500);
  EXPECT_GE(report.image_ms, 80);
  EXPECT_LT(report.image_ms, 1500);
}

// The studio busy for longer than a node may stay silent (the tracker's first frame takes a
// second) while both nodes keep talking: what waits in the socket shows them alive, and neither is
// taken for lost.
TEST(StudioCoordinator, NodesWhoseMessagesWaitWhileTheStudioWorksAreNotLost) {
  StudioCoordinatorOptions options;
  options.lost_after = milliseconds(200);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node1(studio.endpoint(), "node1"), node2(studio.endpoint(), "node2");
  for (int round = 0; round < 3; ++round) {
    ASSERT_TRUE(node1.send(0, HeartbeatData{}));
    ASSERT_TRUE(node2.send(0, HeartbeatData{}));
    std::this_thread::sleep_for(milliseconds(150));  // both messages arrive
    studio.runFor(milliseconds(1));
    std::this_thread::sleep_for(milliseconds(250));  // the studio at work, beyond lost_after
  }
  ASSERT_TRUE(node1.send(0, HeartbeatData{}));
  ASSERT_TRUE(node2.send(0, HeartbeatData{}));
  std::this_thread::sleep_for(milliseconds(150));
  studio.runFor(milliseconds(1));
  for (const NodeReport& node : studio.report().nodes) {
    EXPECT_EQ(node.times_lost, 0) << node.name;
    EXPECT_EQ(studio.nodeState(node.name), "streaming") << node.name;
  }
  // A node that is silent is lost all the same.
  for (int slice = 0; slice < 4; ++slice) {
    ASSERT_TRUE(node1.send(0, HeartbeatData{}));
    studio.runFor(milliseconds(80));
  }
  EXPECT_EQ(studio.nodeState("node1"), "streaming");
  EXPECT_EQ(studio.nodeState("node2"), "lost");
}

// A node lost mid-take and back (its PC restarted) reports no take until its next heartbeat: the
// take it recorded before, its sets written, are not what the new process records.
TEST(StudioCoordinator, ANodeBackFromLostReportsItsTakeAnew) {
  StudioCoordinatorOptions options;
  options.lost_after = milliseconds(200);
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, options);
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint(), "node1");
  const auto take = [&] {
    for (const NodeReport& n : studio.report().nodes)
      if (n.name == "node1") return n.take;
    return TakeStatusData{};
  };
  HeartbeatData recording;
  recording.take = TakeStatusData{"take-1", 10, 0, 12, 0, 1000, false, "", -1, ""};
  ASSERT_TRUE(node.send(0, recording));
  studio.runFor(milliseconds(100));
  EXPECT_EQ(take().written, 12);
  studio.runFor(milliseconds(300));
  ASSERT_EQ(studio.nodeState("node1"), "lost");
  HelloData hello;
  hello.node_name = "node1";
  ASSERT_TRUE(node.send(0, hello));
  studio.runFor(milliseconds(100));
  EXPECT_EQ(studio.nodeState("node1"), "streaming");
  EXPECT_TRUE(take().take.empty());
  EXPECT_EQ(take().written, 0);
  recording.take.written = 3;
  ASSERT_TRUE(node.send(0, recording));
  studio.runFor(milliseconds(100));
  EXPECT_EQ(take().written, 3);
}

// A node's free text (its cameras' errors, its take's error) reaches the log and `lumistage run`'s
// report: with a line break or terminal escapes in it, it is shown escaped and cut short; plain
// text as it was.
TEST(StudioCoordinator, ANodesErrorTextIsShownEscaped) {
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, {});
  StudioCoordinator& studio = *made;
  ScriptedNode node(studio.endpoint(), "node1");
  HeartbeatData heartbeat;
  heartbeat.cameras = {{"cam01", 10, 0, 30.f, "\x1b[2Jlost\n[info] node node2 is streaming"},
                       {"cam02", 10, 0, 30.f, "lost: reconnecting"}};
  heartbeat.take =
      TakeStatusData{"take-1", 1, 9, 0, 0, 0, false, std::string(900, 'e') + "\r", -1, "pc\x1b:1"};
  ASSERT_TRUE(node.send(0, heartbeat));
  const auto report = [&] {
    for (const NodeReport& n : studio.report().nodes)
      if (n.name == "node1") return n;
    return NodeReport{};
  };
  for (int slice = 0; slice < 200 && report().cameras.empty(); ++slice)
    studio.runFor(milliseconds(10));
  const NodeReport n = report();
  ASSERT_EQ(n.cameras.size(), 2u);
  EXPECT_EQ(n.cameras[0].last_error, "'\\x1b[2Jlost\\n[info] node node2 is streaming'");
  EXPECT_EQ(n.cameras[1].last_error, "lost: reconnecting");
  EXPECT_EQ(n.take.error, "'" + std::string(200, 'e') + "'... (901 bytes in all)");
  EXPECT_EQ(n.take.disk, "'pc\\x1b:1'");
}

// Issue 54: every connection to the studio's port, before its handshake is done too, may make it
// buffer a message of the endpoint's limit, which was 64 MB whatever the rig. It now follows from
// the rig, the body and the largest view: enough for a node's image of that view in any encoding,
// and a view larger than that is refused rather than cost every node its connection.
TEST(StudioCoordinator, ItsMessageLimitFollowsTheRigAndTheLargestView) {
  StudioCoordinatorOptions options;
  options.max_view_pixels = 640 * 480;
  // The body gives the statistics' size (without one, any number of points up to the decoder's
  // limit is taken).
  options.body = std::make_shared<const SkinnedMesh>(loadGenericHuman());
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, options);
  StudioCoordinator& studio = *made;
  EXPECT_GE(studio.maxMessageBytes(), size_t(640 * 480) * 5);  // RLE of noise: 5 bytes a pixel
  EXPECT_LT(studio.maxMessageBytes(), size_t{8} << 20);

  ViewData view = studio.view();
  view.width = 640;
  view.height = 480;
  studio.setView(view);
  EXPECT_EQ(studio.view().width, 640);
  view.width = 1280;
  view.height = 960;
  studio.setView(view);
  EXPECT_EQ(studio.view().width, 640);  // refused: the nodes' images would not fit
  view.view = 1;
  studio.setViews({studio.view(), view});
  EXPECT_EQ(studio.views().size(), 1u);

  // A node's largest image of the view arrives.
  ScriptedNode node(studio.endpoint(), "node1");
  std::vector<uint8_t> noise(size_t(640) * 480 * 4);
  for (size_t i = 0; i < noise.size(); ++i) noise[i] = uint8_t(i * 7 + i / 4 * 13 + 1);
  ASSERT_TRUE(
      node.send(0, PartialImageData{0, 640, 480, ImageEncoding::kRleRgba, encodeRleRgba(noise)}));
  for (int slice = 0; slice < 200 && studio.nodeState("node1") != "streaming"; ++slice)
    studio.runFor(milliseconds(10));
  EXPECT_EQ(studio.nodeState("node1"), "streaming");
  EXPECT_EQ(badMessagesOf(studio, "node1"), 0);
}

// How long each node's takes' disk lasts at its cameras' rate: nodes on one PC write to one disk,
// so its free space lasts for their rates together; a node that does not say has no figure.
TEST(StudioCoordinator, TakesDiskTimeCountsTheNodesThatShareADisk) {
  const std::unique_ptr<StudioCoordinator> made = twoCameraStudio(1, {});
  StudioCoordinator& studio = *made;
  ScriptedNode node1(studio.endpoint(), "node1"), node2(studio.endpoint(), "node2");
  const auto secondsLeft = [&](const std::string& name) {
    for (const NodeReport& n : studio.report().nodes)
      if (n.name == name) return n.take_seconds_left;
    return -2.0;
  };
  // Each node: one 160x120 camera of one byte a pixel at 25 frames a second, 480 kB/s; disks
  // with ten minutes of that free.
  constexpr int64_t kTenMinutes = int64_t(160) * 120 * 25 * 600;
  const auto heartbeat = [&](ScriptedNode& node, const std::string& camera, const std::string& disk,
                             int64_t free) {
    HeartbeatData h;
    h.cameras.push_back({camera, 100, 0, 25.f, ""});
    h.take.free_bytes = free;
    h.take.disk = disk;
    ASSERT_TRUE(node.send(0, h));
  };
  heartbeat(node1, "cam01", "stage-pc:1", kTenMinutes);
  heartbeat(node2, "cam02", "stage-pc:1", kTenMinutes);
  studio.runFor(milliseconds(200));
  EXPECT_NEAR(secondsLeft("node1"), 300, 1);  // one disk, both nodes' takes
  EXPECT_NEAR(secondsLeft("node2"), 300, 1);
  heartbeat(node2, "cam02", "node2-pc:1", kTenMinutes / 2);
  studio.runFor(milliseconds(200));
  EXPECT_NEAR(secondsLeft("node1"), 600, 1);  // a disk of its own
  EXPECT_NEAR(secondsLeft("node2"), 300, 1);
  heartbeat(node2, "cam02", "", -1);  // a node that records no takes
  studio.runFor(milliseconds(200));
  EXPECT_EQ(secondsLeft("node2"), -1);
  EXPECT_NEAR(secondsLeft("node1"), 600, 1);
}

}  // namespace
}  // namespace lumistage
