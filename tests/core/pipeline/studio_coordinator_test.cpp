#include "core/pipeline/studio_coordinator.h"

#include <gtest/gtest.h>

#include <thread>

#include "core/body/human_model.h"
#include "core/body/human_skeleton.h"
#include "core/geometry/ring_rig.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/posed_body.h"
#include "core/refine/refinement_statistics.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {
namespace {

using std::chrono::milliseconds;

// The studio's side of one frame, with a node played by the test over the real transport: the
// node answers what it chooses, and the test sees what the studio makes of it.
class ScriptedNode {
 public:
  explicit ScriptedNode(const std::string& studio, const std::string& name = "node1")
      : name_(name), endpoint_([&] {
          NodeEndpointConfig config;
          config.connect = studio;
          config.name = name;
          config.security = TransportSecurity::kPlain;
          return config;
        }()) {}

  // `sent_ns`: the node's clock at capture (0: now).
  bool send(int64_t frame_id, MessageBody body, int64_t sent_ns = 0) {
    Message m;
    m.sender = name_;
    m.frame_id = frame_id;
    m.sent_ns = sent_ns != 0 ? sent_ns : wallNowNs();
    m.body = std::move(body);
    return endpoint_.send(m, milliseconds(3000));
  }
  // The next message of the kind T from the studio, running it meanwhile (`slices` of 10 ms).
  template <typename T>
  std::optional<Message> await(StudioCoordinator& studio, int slices = 300) {
    for (int slice = 0; slice < slices; ++slice) {
      studio.runFor(milliseconds(10));
      if (std::optional<DecodeResult> in = endpoint_.receive(milliseconds(0));
          in && in->ok() && std::holds_alternative<T>(in->message->body)) {
        return *in->message;
      }
    }
    return std::nullopt;
  }

 private:
  std::string name_;
  NodeEndpoint endpoint_;
};

// A studio (plain transport, a free port) for a ring of two 160x120 cameras.
std::unique_ptr<StudioCoordinator> twoCameraStudio(int cameras_per_node,
                                                   const StudioCoordinatorOptions& options) {
  RingRigSpec spec;
  spec.cameras = 2;
  spec.cameras_per_node = cameras_per_node;
  spec.width = 160;
  spec.height = 120;
  StudioEndpointConfig config;
  config.bind = "tcp://127.0.0.1:*";
  config.security = TransportSecurity::kPlain;
  return std::make_unique<StudioCoordinator>(makeRingRig(spec), config, kHumanJointCount, options);
}

// A node's statistics message for `stats` (made with `refine`'s offset count).
VertexStatisticsData statisticsMessage(const RefinementStatistics& stats,
                                       const RefineConfig& refine) {
  VertexStatisticsData message{uint32_t(stats.vertex_count), refine.offset_count, {}};
  encodeRefinementStatistics(stats, message.packed);
  return message;
}

// A node's image of `view`: one pixel drawn, fully weighted, of red level `red`.
PartialImageData onePixelImage(const ViewData& view, uint8_t red = 0) {
  PartialImageData image{view.view, view.width, view.height, ImageEncoding::kRawRgba,
                         std::vector<uint8_t>(size_t(view.width) * view.height * 4, 0)};
  image.data[0] = red, image.data[3] = 255;
  return image;
}

// Runs the studio until `frames` frames are done, for at most `slices` of 10 ms.
int64_t framesDoneAfter(StudioCoordinator& studio, int64_t frames, int slices) {
  for (int slice = 0; slice < slices && studio.framesDone() < frames; ++slice)
    studio.runFor(milliseconds(10));
  return studio.framesDone();
}

int64_t badMessagesOf(const StudioCoordinator& studio, const std::string& name) {
  for (const NodeReport& n : studio.report().nodes)
    if (n.name == name) return n.bad_messages;
  return -1;
}

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
    return SilhouetteMaskData{0, w, h, std::vector<uint8_t>(size_t(w * h + 7) / 8, 0)};
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

// The next pose the studio sends `node`, for a frame at or after `frame_id`.
std::optional<int64_t> nextPoseFrame(ScriptedNode& node, StudioCoordinator& studio,
                                     int64_t frame_id) {
  for (int k = 0; k < 8; ++k) {
    const std::optional<Message> pose = node.await<PoseData>(studio);
    if (!pose) return std::nullopt;
    if (pose->frame_id >= frame_id) return pose->frame_id;
  }
  return std::nullopt;
}

// A studio of two one-camera nodes played by the test, each node's silhouettes of `first_frame`
// sent and the pose for it back.
struct TwoNodeStudio {
  explicit TwoNodeStudio(milliseconds deadline, int64_t first_frame = 1)
      : made(twoCameraStudio(1,
                             [&] {
                               StudioCoordinatorOptions options;
                               options.deadline = deadline;
                               return options;
                             }())),
        studio(*made),
        node1(studio.endpoint(), "node1"),
        node2(studio.endpoint(), "node2"),
        first(first_frame) {
    EXPECT_TRUE(both(first_frame));
    EXPECT_EQ(nextPoseFrame(node1, studio, first_frame), first_frame);
    RefinementStatistics stats;
    stats.reset(10, refine.offset_count, refine.colour_bits);
    statistics = statisticsMessage(stats, refine);
  }
  bool both(int64_t frame_id) {
    return node1.send(frame_id, SilhouettesData{}) && node2.send(frame_id, SilhouettesData{});
  }
  // Both nodes' silhouettes of `frame_id` sent (the first frame's were) and node1 sent its pose.
  bool posed(int64_t frame_id) {
    return frame_id == first ||
           (both(frame_id) && nextPoseFrame(node1, studio, frame_id) == frame_id);
  }
  std::unique_ptr<StudioCoordinator> made;
  StudioCoordinator& studio;
  ScriptedNode node1, node2;
  const int64_t first;
  const RefineConfig refine;
  VertexStatisticsData statistics;  // of 10 vertices, nothing seen
};

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
    return SilhouetteMaskData{camera, w, h, std::vector<uint8_t>(size_t(w * h + 7) / 8, 0)};
  };
  ASSERT_TRUE(two.node1.send(2, SilhouettesData{{mask(0), mask(1), mask(0)}}));
  ASSERT_TRUE(two.node2.send(2, SilhouettesData{{mask(1)}}));
  EXPECT_EQ(nextPoseFrame(two.node1, two.studio, 2), 2);
  EXPECT_EQ(badMessagesOf(two.studio, "node1"), 2);
  EXPECT_EQ(badMessagesOf(two.studio, "node2"), 0);
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
