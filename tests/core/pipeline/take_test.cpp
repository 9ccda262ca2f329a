// Takes recorded on the nodes (TakeRecorder) and joined into one session (mergeTake), with real
// files: each node's part holds exactly the frames asked of it, bit-exact, and the parts merge
// into the session of every camera.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/base/output_path.h"
#include "core/capture/session_reader.h"
#include "core/capture/take_merge.h"
#include "core/pipeline/take_recorder.h"
#include "tests/core/capture/capture_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using namespace lumistage::test;

// Three 64x48 cameras, one a node (node1..node3).
Rig takeRig() {
  return smallRig(/*cameras_per_node=*/1);
}

// Node n's set of frame f: its camera's image of frameImages(rig, mono8, f).
std::vector<CameraFrame> nodeSet(const Rig& rig, int node, int64_t f) {
  const int camera = rig.nodes()[node].cameras[0];
  std::vector<CameraFrame> set(1);
  set[0].camera = camera;
  set[0].frame_id = f;
  set[0].timestamp_ns = timestampOf(f);
  set[0].image = frameImages(rig, PixelFormat::kMono8, f)[camera];
  return set;
}

// Offers a node's frames as its capture loop does: by pointer.
void offerSet(TakeRecorder& recorder, int64_t f, const std::vector<CameraFrame>& set) {
  std::vector<const CameraFrame*> frames;
  for (const CameraFrame& frame : set) frames.push_back(&frame);
  recorder.offer(f, frames);
}

// Waits (at most 10 s) until the recorder has closed its take.
TakeStatusData finished(const TakeRecorder& recorder) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!recorder.status().finished && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return recorder.status();
}

TEST(Take, NodesRecordTheAskedFramesAndTheirPartsMergeBitExact) {
  const Rig rig = takeRig();
  const fs::path folder = testing::testFolder("take");
  const fs::path takes = folder / "takes";
  std::vector<std::unique_ptr<TakeRecorder>> nodes;
  for (const RigNode& node : rig.nodes())
    nodes.push_back(std::make_unique<TakeRecorder>(takes, rig, node.name, 30.0));
  // Before any take, each says how much its disk holds, and which disk that is: the same one for
  // the three nodes on this machine.
  for (auto& node : nodes) {
    EXPECT_NEAR(double(node->status().free_bytes), double(diskSpaceAt(folder).free_bytes),
                0.01 * double(diskSpaceAt(folder).free_bytes));
    EXPECT_EQ(node->status().disk, diskSpaceAt(folder).disk);
  }
  for (auto& node : nodes) node->command({"take-1", 5});
  for (int64_t f = 0; f < 20; ++f) {
    if (f == 10) nodes[0].reset();  // node1's PC loses power after frame 9
    if (f == 12) {
      // node1 is back (its service restarted) and told the take again at its first heartbeat.
      nodes[0] = std::make_unique<TakeRecorder>(takes, rig, "node1", 30.0);
      nodes[0]->command({"take-1", 5});
      for (auto& node : nodes) node->command({"take-1", 5, 14});  // the stop
    }
    for (int n = 0; n < 3; ++n) {
      if (!nodes[n] || (n == 2 && f == 8)) continue;  // node3's cameras lost frame 8
      offerSet(*nodes[n], f, nodeSet(rig, n, f));
    }
  }
  const int written[3] = {3, 10, 9};  // node1 since its restart
  // Frames of the take not in a node's part are counted: node1's 10 and 11 (its PC was off; 5 to
  // 9 are in its first part), node3's 8.
  const int dropped[3] = {2, 0, 1};
  for (int n = 0; n < 3; ++n) {
    const TakeStatusData status = finished(*nodes[n]);
    EXPECT_TRUE(status.finished);
    EXPECT_EQ(status.take, "take-1");
    EXPECT_EQ(status.first_frame, 5);
    EXPECT_EQ(status.last_frame, 14);
    EXPECT_EQ(status.written, written[n]);
    EXPECT_EQ(status.dropped, dropped[n]) << n;
    EXPECT_GT(status.bytes, 0);
    EXPECT_EQ(status.error, "");
  }
  nodes.clear();
  // Each part: a session of its node's own camera with the frames asked for, bit-exact; node1's
  // first part intact up to the power cut, the rest beside it.
  const std::vector<std::pair<std::string, std::vector<int64_t>>> expected = {
      {"node1", {5, 6, 7, 8, 9}},
      {"node1-2", {12, 13, 14}},
      {"node2", {5, 6, 7, 8, 9, 10, 11, 12, 13, 14}},
      {"node3", {5, 6, 7, 9, 10, 11, 12, 13, 14}}};
  for (const auto& [name, ids] : expected) {
    const SessionReader part(takes / "take-1" / name);
    const int node = name[4] - '1';
    const int camera = rig.nodes()[node].cameras[0];
    ASSERT_EQ(part.rig().cameraCount(), 1);
    EXPECT_EQ(part.rig().camera(0).name(), rig.camera(camera).name());
    EXPECT_EQ(part.imageFiles(), ImageFiles::kPnm);  // raw pixels: no encoding to keep up with
    EXPECT_EQ(part.rig().nodes()[0].name, rig.nodes()[node].name);
    ASSERT_EQ(part.frameCount(), static_cast<int>(ids.size())) << name;
    std::vector<CameraFrame> frames;
    for (int i = 0; i < part.frameCount(); ++i) {
      EXPECT_EQ(part.frameId(i), ids[i]) << name;
      part.readFrame(i, frames);
      EXPECT_EQ(frames[0].image.pixels,
                frameImages(rig, PixelFormat::kMono8, ids[i])[camera].pixels);
    }
  }

  const std::vector<fs::path> parts = takeParts({takes / "take-1"});
  ASSERT_EQ(parts.size(), 4u);
  const TakeMergeReport report = mergeTake(parts, folder / "merged", rig);
  // Frame 8 is not in node3's part, 10 and 11 not in node1's.
  const std::vector<int64_t> common = {5, 6, 7, 9, 12, 13, 14};
  EXPECT_EQ(report.frames, 7);
  ASSERT_EQ(report.notes.size(), 3u);
  EXPECT_NE(report.notes[0].find("node1: 1 of its 8 frames are not in every part"),
            std::string::npos)
      << report.notes[0];
  // The parts' files copied as they are, or kept as PNG (decoded and encoded): the same frames.
  EXPECT_EQ(mergeTake(parts, folder / "merged-png", rig, ImageFiles::kPng).frames, 7);
  for (const char* out : {"merged", "merged-png"}) {
    const SessionReader merged(folder / out);
    EXPECT_EQ(merged.rig(), rig);
    EXPECT_EQ(merged.imageFiles(),
              out == std::string("merged") ? ImageFiles::kPnm : ImageFiles::kPng);
    ASSERT_EQ(merged.frameCount(), 7);
    std::vector<CameraFrame> frames;
    for (int i = 0; i < merged.frameCount(); ++i) {
      const int64_t f = merged.frameId(i);
      EXPECT_EQ(f, common[i]);
      // Across node1's restart too, within a nanosecond of rounding.
      EXPECT_NEAR(double(merged.timestampNs(i)), double(timestampOf(f) - timestampOf(5)), 1.0) << f;
      merged.readFrame(i, frames);
      const std::vector<Image> truth = frameImages(rig, PixelFormat::kMono8, f);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(frames[c].image.pixels, truth[c].pixels) << out << " " << f << " " << c;
    }
  }
}

TEST(Take, ANodeSaysWhyItRecordsNothingAndLosesNothing) {
  const Rig rig = takeRig();
  const fs::path folder = testing::testFolder("take");

  // Started without a takes folder.
  TakeRecorder nowhere({}, rig, "node1", 30.0);
  nowhere.command({"take-1", 0});
  offerSet(nowhere, 0, nodeSet(rig, 0, 0));
  EXPECT_EQ(nowhere.status().error, "this node records no takes: start it with --takes FOLDER");
  EXPECT_TRUE(nowhere.status().finished);
  EXPECT_EQ(nowhere.status().written, 0);
  EXPECT_EQ(nowhere.status().free_bytes, -1);  // no disk to tell of
  EXPECT_TRUE(nowhere.status().disk.empty());

  // The take's folder holds files already (a take of that name, recorded before): untouched.
  const fs::path old = folder / "takes" / "take-1" / "node1";
  fs::create_directories(old);
  std::ofstream(old / "keep.txt") << "an earlier take";
  TakeRecorder taken(folder / "takes", rig, "node1", 30.0);
  taken.command({"take-1", 0});
  offerSet(taken, 0, nodeSet(rig, 0, 0));
  const TakeStatusData status = taken.status();
  EXPECT_NE(status.error.find(old.string()), std::string::npos) << status.error;
  EXPECT_TRUE(status.finished);
  EXPECT_EQ(readFile(old / "keep.txt"), "an earlier take");

  // A new take closes the open one, complete; no take (an empty name) closes it too, and says
  // so only once what was queued is on the disk.
  TakeRecorder recorder(folder / "takes", rig, "node2", 30.0);
  recorder.command({"a", 0});
  for (int64_t f = 0; f < 4; ++f) offerSet(recorder, f, nodeSet(rig, 1, f));
  recorder.command({"b", 0});
  EXPECT_EQ(recorder.status().take, "b");
  EXPECT_EQ(recorder.status().written, 0);
  for (int64_t f = 4; f < 6; ++f) offerSet(recorder, f, nodeSet(rig, 1, f));
  recorder.command({});
  EXPECT_TRUE(finished(recorder).finished);
  offerSet(recorder, 6, nodeSet(rig, 1, 6));
  EXPECT_EQ(SessionReader(folder / "takes" / "a" / "node2").frameCount(), 4);
  EXPECT_EQ(SessionReader(folder / "takes" / "b" / "node2").frameCount(), 2);

  // The studio restarted and asks for a take of the same name again (from another frame): nothing
  // is written into the earlier take, and the node says why, whether it still knows the name (it
  // showed the earlier take as done and wrote nothing, without a word) or finds it on its disk
  // (node restarted too: a second part was written beside the first, and the merge joined them).
  TakeRecorder third(folder / "takes", rig, "node3", 30.0);
  third.command({"c", 0, 2});  // stopped after frame 2, as the studio stops a take
  for (int64_t f = 0; f < 4; ++f) offerSet(third, f, nodeSet(rig, 2, f));
  EXPECT_TRUE(finished(third).error.empty());
  for (int restarted = 0; restarted < 2; ++restarted) {
    SCOPED_TRACE(restarted);
    TakeRecorder fresh(folder / "takes", rig, "node3", 30.0);
    TakeRecorder& node = restarted ? fresh : third;
    node.command({"c", 100});
    for (int64_t f = 100; f < 103; ++f) offerSet(node, f, nodeSet(rig, 2, f));
    const TakeStatusData again = finished(node);
    EXPECT_NE(again.error.find("a take named c was recorded"), std::string::npos) << again.error;
    EXPECT_NE(again.error.find("from frame 0: this one (from frame 100) needs another name"),
              std::string::npos)
        << again.error;
    EXPECT_EQ(again.written, 0);
    EXPECT_EQ(again.first_frame, 100);
  }
  EXPECT_EQ(SessionReader(folder / "takes" / "c" / "node3").frameCount(), 3);
  EXPECT_FALSE(fs::exists(folder / "takes" / "c" / "node3-2"));
}

// The take's frames that never reach a node's recorder (the command heard after its first
// frames, a capture that fell behind and missed frames, a camera silent) are counted with the
// dropped ones, so that a part short of frames never reports none dropped.
TEST(Take, FramesOfTheTakeThatNeverCameAreCountedAsDropped) {
  const Rig rig = takeRig();
  const fs::path folder = testing::testFolder("take");
  TakeRecorder recorder(folder / "takes", rig, "node1", 30.0);
  recorder.command({"gaps", 10, 19});
  for (int64_t f : {12, 13, 15, 18}) offerSet(recorder, f, nodeSet(rig, 0, f));
  // Sets come in increasing ids: 10, 11, 14, 16 and 17 will not come now; 19 still may.
  EXPECT_EQ(recorder.status().dropped, 5);
  offerSet(recorder, 25, nodeSet(rig, 0, 25));  // past the last frame: the take closes
  const TakeStatusData status = finished(recorder);
  EXPECT_EQ(status.written, 4);
  EXPECT_EQ(status.dropped, 6);  // 10, 11, 14, 16, 17, 19
  EXPECT_EQ(SessionReader(folder / "takes" / "gaps" / "node1").frameCount(), 4);
}

// Takes stopped and started in quick succession, each closed while the ones before may still be
// writing their queues (PNG, slower to write than the sets come): closing one does not wait for
// another, every take's part ends whole with exactly its frames, and the node says the takes are
// finished only once all of them are on the disk.
TEST(Take, TakesClosedInQuickSuccessionAllEndWhole) {
  RingRigSpec spec;  // three cameras, one a node, of noise that PNG is slow to write
  spec.cameras = 3;
  spec.cameras_per_node = 1;
  spec.width = 320;
  spec.height = 240;
  const Rig rig = makeRingRig(spec);
  const fs::path folder = testing::testFolder("take");
  constexpr int kTakes = 6, kSets = 5;
  const int camera = rig.nodes()[0].cameras[0];
  std::vector<std::vector<CameraFrame>> sets;  // made first: offered as fast as cameras give them
  for (int64_t f = 0; f < kTakes * kSets; ++f) sets.push_back(nodeSet(rig, 0, f));
  {
    TakeRecorder recorder(folder / "takes", rig, "node1", 30.0, ImageFiles::kPng);
    for (int t = 0; t < kTakes; ++t) {
      recorder.command({fmt::format("t{}", t), t * kSets});
      for (int64_t f = t * kSets; f < (t + 1) * kSets; ++f) offerSet(recorder, f, sets[f]);
      EXPECT_FALSE(recorder.status().finished) << t;  // open
    }
    recorder.command({});
    const TakeStatusData status = finished(recorder);
    EXPECT_TRUE(status.finished);
    EXPECT_EQ(status.take, "");
    EXPECT_EQ(status.error, "");
    // Every take is on the disk once finished says so, before the recorder is gone.
    for (int t = 0; t < kTakes; ++t) {
      const SessionReader part(folder / "takes" / fmt::format("t{}", t) / "node1");
      ASSERT_EQ(part.frameCount(), kSets) << t;
      std::vector<CameraFrame> frames;
      for (int i = 0; i < kSets; ++i) {
        EXPECT_EQ(part.frameId(i), t * kSets + i);
        part.readFrame(i, frames);
        EXPECT_EQ(frames[0].image.pixels,
                  frameImages(rig, PixelFormat::kMono8, t * kSets + i)[camera].pixels);
      }
    }
    // Another round, the recorder destroyed while the last take may still be writing: it ends
    // whole too.
    recorder.command({"last", kTakes * kSets});
    for (int64_t f = 0; f < kSets; ++f) offerSet(recorder, kTakes * kSets + f, sets[f]);
  }
  EXPECT_EQ(SessionReader(folder / "takes" / "last" / "node1").frameCount(), kSets);
}

// A merge cut short (here a full disk, as far as the merge's writes go) leaves nothing under its
// name, where a shorter session used to open without a word; the parts stay whole, and the merge
// done again puts the session in place.
TEST(Take, AMergeCutShortLeavesNothingUnderItsName) {
  const Rig rig = takeRig();
  const fs::path folder = testing::testFolder("take_cut");
  std::vector<std::unique_ptr<TakeRecorder>> nodes;
  for (const RigNode& node : rig.nodes())
    nodes.push_back(std::make_unique<TakeRecorder>(folder / "takes", rig, node.name, 30.0));
  for (auto& node : nodes) node->command({"t", 0, 4});
  for (int64_t f = 0; f < 6; ++f)
    for (int n = 0; n < 3; ++n) offerSet(*nodes[n], f, nodeSet(rig, n, f));
  for (auto& node : nodes) ASSERT_TRUE(finished(*node).error.empty());
  std::vector<fs::path> parts;
  for (const RigNode& node : rig.nodes()) parts.push_back(folder / "takes" / "t" / node.name);
  const fs::path out = folder / "merged";
  const int code = testing::inChildProcess([&] {
    testing::limitFileSize(2000);  // less than an image
    try {
      mergeTake(parts, out);
    } catch (const Error&) {
      return 1;
    }
    return 0;
  });
  EXPECT_EQ(code, 1);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(folder / "merged.partial"));
  EXPECT_EQ(mergeTake(parts, out).frames, 5);
  EXPECT_EQ(SessionReader(out).frameCount(), 5);
  // Named with a trailing slash, or an empty folder made for it (a mount point): in place there.
  EXPECT_EQ(mergeTake(parts, (folder / "slash").string() + "/").frames, 5);
  EXPECT_EQ(SessionReader(folder / "slash").frameCount(), 5);
  fs::create_directories(folder / "mounted");
  EXPECT_EQ(mergeTake(parts, folder / "mounted").frames, 5);
  EXPECT_EQ(SessionReader(folder / "mounted").frameCount(), 5);
  fs::create_directories(folder / "mounted_full");
  EXPECT_EQ(testing::inChildProcess([&] {
              testing::limitFileSize(2000);
              try {
                mergeTake(parts, folder / "mounted_full");
              } catch (const Error&) {
                return 1;
              }
              return 0;
            }),
            1);
  EXPECT_TRUE(fs::is_directory(folder / "mounted_full"));
  EXPECT_TRUE(fs::is_empty(folder / "mounted_full"));  // emptied again: nothing under the name
  fs::remove_all(folder);
}

TEST(Take, PartsThatDoNotBelongTogetherAreRefusedByName) {
  const Rig rig = takeRig();
  const fs::path folder = testing::testFolder("take");
  // Each part a session of one node's camera.
  auto part = [&](const std::string& name, int node, PixelFormat format, int64_t first, int count,
                  ImageFiles files = ImageFiles::kPng) {
    const int camera = rig.nodes()[node].cameras[0];
    SessionWriter writer(folder / name, nodeRig(rig, rig.nodes()[node].name), format, 30.0, "test",
                         {}, files);
    for (int64_t f = first; f < first + count; ++f)
      writer.writeFrame(f, timestampOf(f), {frameImages(rig, format, f)[camera].view()});
    return folder / name;
  };
  const fs::path a = part("a", 0, PixelFormat::kMono8, 0, 3);
  const fs::path b = part("b", 1, PixelFormat::kMono8, 2, 3);
  const fs::path rgb = part("rgb", 2, PixelFormat::kRgb8, 0, 3);
  const fs::path late = part("late", 2, PixelFormat::kMono8, 5, 3);
  const fs::path pnm = part("pnm", 1, PixelFormat::kMono8, 0, 3, ImageFiles::kPnm);
  // A part of the first two cameras (another rig's node): cam01 would be in two nodes.
  const fs::path pair = folder / "pair";
  {
    const Rig pair_rig({rig.camera(0), rig.camera(1)}, {RigNode{"node1", "", {0, 1}}});
    SessionWriter writer(pair, pair_rig, PixelFormat::kMono8, 30.0, "test");
    const std::vector<Image> images = frameImages(rig, PixelFormat::kMono8, 0);
    writer.writeFrame(0, 0, {images[0].view(), images[1].view()});
  }

  EXPECT_EQ(testing::errorOf([&] {
              mergeTake({a, rgb}, folder / "out1");
            }),
            "take: " + rgb.string() + ": rgb8 at 30 fps in png files, but " + a.string() +
                " is mono8 at 30 fps in png files");
  EXPECT_EQ(testing::errorOf([&] {
              mergeTake({a, pnm}, folder / "out0");
            }),
            "take: " + pnm.string() + ": mono8 at 30 fps in pnm files, but " + a.string() +
                " is mono8 at 30 fps in png files");
  EXPECT_EQ(testing::errorOf([&] {
              mergeTake({a, pair}, folder / "out2");
            }),
            "take: camera " + rig.camera(0).name() + " is in both " + a.string() + " and " +
                pair.string() + " with other cameras");
  EXPECT_EQ(testing::errorOf([&] {
              mergeTake({a, late}, folder / "out3");
            }),
            "take: the 2 parts have no frame in common (first part: " + a.string() + ")");
  EXPECT_EQ(testing::errorOf([&] {
              mergeTake({a, b}, folder / "out4", rig);
            }),
            "take: the rig's camera " + rig.camera(2).name() + " is in none of the parts");
  {  // A rig whose first camera is of another size than the part filmed.
    std::vector<Camera> cameras = rig.cameras();
    const Camera c = cameras[0];
    cameras[0] = Camera(c.name(), 2 * c.width(), 2 * c.height(), c.intrinsics(), c.distortion(),
                        c.rotation(), c.translation());
    const Rig other(cameras, rig.nodes());
    EXPECT_EQ(testing::errorOf([&] {
                mergeTake({a, b}, folder / "out6", other);
              }),
              fmt::format("take: the rig's camera {} is {}x{}, its part filmed {}x{}", c.name(),
                          2 * c.width(), 2 * c.height(), c.width(), c.height()));
  }
  EXPECT_NE(testing::errorOf([&] { takeParts({folder / "nothing"}); }).find("no such folder"),
            std::string::npos);
  // Frames 2 of a and b in common; the out folder must be new.
  EXPECT_EQ(mergeTake({a, b}, folder / "out5").frames, 1);
  EXPECT_NE(testing::errorOf([&] {
              mergeTake({a, b}, folder / "out5");
            }).find("out5"),
            std::string::npos);
  EXPECT_EQ(SessionReader(folder / "out5").frameCount(), 1);
}

}  // namespace
}  // namespace lumistage
