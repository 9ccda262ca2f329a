// The camera node's capture side, in process, with a source the test controls and the studio's
// endpoint played by the test over the real transport.
#include "core/pipeline/camera_node.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <functional>
#include <thread>

#include "core/body/human_model.h"
#include "core/capture/session_reader.h"
#include "core/net/transport.h"
#include "tests/core/refine/refine_test_scene.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using std::chrono::milliseconds;

// Frame `id` of `camera`, at 30 fps, every pixel of one RGB colour.
void fillFrame(const Rig& rig, int camera, int64_t id, const std::array<uint8_t, 3>& rgb,
               CameraFrame& frame) {
  frame.camera = camera;
  frame.frame_id = id;
  frame.timestamp_ns = id * 33'333'333;
  const Camera& c = rig.camera(camera);
  frame.image.resize(PixelFormat::kRgb8, c.width(), c.height());
  for (size_t p = 0; p + 2 < frame.image.pixels.size(); p += 3)
    std::copy(rgb.begin(), rgb.end(), &frame.image.pixels[p]);
}

// The frames of a node's cameras, every camera of every frame in turn (a screen-green image), a
// frame every 5 ms; from frame `dies_at` on, camera `dead` delivers nothing (unplugged); before
// frame `dark_until` every image is black (lens caps on); after `restart_at` frames the cameras
// count from 0 again (all of them reopened after a power cut); from frame `dim_from` to
// `dim_until` the screen is lit a fifth as bright (its green excess 18 levels instead of 90).
class ScriptedSource : public FrameSource {
 public:
  ScriptedSource(Rig rig, std::vector<int> cameras, int dead, int64_t dies_at,
                 int64_t dark_until = 0, int64_t restart_at = -1, int64_t dim_from = -1,
                 int64_t dim_until = -1)
      : rig_(std::move(rig)),
        cameras_(std::move(cameras)),
        dead_(dead),
        dies_at_(dies_at),
        dark_until_(dark_until),
        restart_at_(restart_at),
        dim_from_(dim_from),
        dim_until_(dim_until) {}
  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, milliseconds) override {
    for (;;) {
      const int camera = cameras_[next_ % cameras_.size()];
      int64_t id = int64_t(next_ / cameras_.size());
      if (restart_at_ >= 0 && id >= restart_at_) id -= restart_at_;
      ++next_;
      if (camera == dead_ && id >= dies_at_) continue;
      if (next_ % cameras_.size() == 0) std::this_thread::sleep_for(milliseconds(5));
      const bool dark = id < dark_until_, dim = id >= dim_from_ && id < dim_until_;
      const uint8_t r = dark  ? 0
                        : dim ? 8
                              : 40,
                    g = dark  ? 0
                        : dim ? 30
                              : 150,
                    b = dark  ? 0
                        : dim ? 12
                              : 60;
      fillFrame(rig_, camera, id, {r, g, b}, frame);
      return true;
    }
  }
  CameraStats stats(int) const override { return {}; }

 private:
  Rig rig_;
  std::vector<int> cameras_;
  int dead_;
  int64_t dies_at_, dark_until_, restart_at_, dim_from_, dim_until_;
  size_t next_ = 0;
};

// Screen-green frames of a node's cameras, a set every 10 ms, in which camera `late`'s frames of
// ids in [late_from, late_until) come `late_by` sets after the others' (a loaded PC's thread);
// the sets' ids go up by `stride` (a slow reader that skips frames).
class LateCameraSource : public FrameSource {
 public:
  LateCameraSource(Rig rig, std::vector<int> cameras, int late, int64_t late_from,
                   int64_t late_until, int64_t late_by, int64_t stride = 1)
      : rig_(std::move(rig)),
        cameras_(std::move(cameras)),
        late_(late),
        late_from_(late_from),
        late_until_(late_until),
        late_by_(late_by),
        stride_(stride) {}
  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, milliseconds) override {
    for (;;) {
      const size_t k = next_ % cameras_.size();
      const int64_t id = int64_t(next_ / cameras_.size()) * stride_;
      int camera = cameras_[k];
      int64_t frame_id = id;
      if (!held_.empty() && held_.front() + late_by_ * stride_ <= id && k == 0) {
        camera = late_, frame_id = held_.front();  // a late frame, before this set's
        held_.erase(held_.begin());
      } else {
        ++next_;
        if (next_ % cameras_.size() == 0) std::this_thread::sleep_for(milliseconds(10));
        if (camera == late_ && id >= late_from_ && id < late_until_) {
          held_.push_back(id);
          continue;
        }
      }
      fillFrame(rig_, camera, frame_id, {40, 150, uint8_t(60 + frame_id % 7)}, frame);
      return true;
    }
  }
  CameraStats stats(int) const override { return {}; }

 private:
  Rig rig_;
  std::vector<int> cameras_;
  int late_;
  int64_t late_from_, late_until_, late_by_, stride_;
  size_t next_ = 0;
  std::vector<int64_t> held_;
};

// A node's cameras as a replay paced by the clock delivers them: each call of next() waits 5 ms
// (its timeout, the node holding the source meanwhile) and three calls in four find no frame due
// yet; screen-green frames. Counts the calls, and where the count stood when the cameras' health
// was last asked for.
class WaitingSource : public FrameSource {
 public:
  WaitingSource(Rig rig, std::vector<int> cameras)
      : rig_(std::move(rig)), cameras_(std::move(cameras)) {}
  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, milliseconds) override {
    std::this_thread::sleep_for(milliseconds(5));
    const int64_t n = calls_++;
    if (n % 4 != 0) return false;
    const int64_t k = n / 4;
    fillFrame(rig_, cameras_[size_t(k) % cameras_.size()], k / int64_t(cameras_.size()),
              {40, 150, 60}, frame);
    return true;
  }
  CameraStats stats(int) const override {
    calls_at_health_ = calls_.load();
    return {};
  }
  int64_t calls() const { return calls_; }
  int64_t callsAtHealth() const { return calls_at_health_; }

 private:
  Rig rig_;
  std::vector<int> cameras_;
  std::atomic<int64_t> calls_{0};
  mutable std::atomic<int64_t> calls_at_health_{0};
};

// A node of the small ring's first node's cameras, talking to a studio endpoint the test holds.
struct NodeUnderTest {
  explicit NodeUnderTest(
      std::function<std::unique_ptr<FrameSource>(const Rig&, std::vector<int>)> make_source,
      CameraNodeOptions options = {})
      : rig(testing::smallRing()),
        studio([] {
          StudioEndpointConfig config;
          config.bind = "tcp://127.0.0.1:*";
          config.security = TransportSecurity::kPlain;
          return config;
        }()),
        cameras(rig.nodes().front().cameras),
        node(
            rig, rig.nodes().front().name, make_source(rig, cameras),
            [&] {
              NodeEndpointConfig endpoint;
              endpoint.connect = studio.endpoint();
              endpoint.name = rig.nodes().front().name;
              endpoint.security = TransportSecurity::kPlain;
              return endpoint;
            }(),
            loadGenericHuman(), std::move(options)),
        running([this] { node.run(stop); }) {}
  ~NodeUnderTest() {
    stop = true;
    running.join();
  }
  // Hands every message the node sends to `take` until it returns true or 20 s pass.
  bool receiveUntil(const std::function<bool(const Message&)>& take,
                    std::chrono::seconds within = std::chrono::seconds(20)) {
    const auto deadline = std::chrono::steady_clock::now() + within;
    while (std::chrono::steady_clock::now() < deadline) {
      const std::optional<ReceivedMessage> in = studio.receive(milliseconds(100));
      if (in && in->result.ok() && take(*in->result.message)) return true;
    }
    return false;
  }

  Rig rig;
  StudioEndpoint studio;
  std::vector<int> cameras;
  std::atomic<bool> stop{false};
  CameraNode node;
  std::thread running;
};

// One of a node's cameras stops delivering (its cable pulled): the node's sets go out with the
// others, whose silhouettes keep reaching the studio, instead of every set waiting for the dead
// camera and being dropped.
TEST(CameraNode, ACameraThatStopsDeliveringDoesNotSilenceItsNode) {
  static constexpr int64_t kDiesAt = 20;
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    const int dead = cameras.at(1);
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), dead, kDiesAt);
  });
  size_t masks_before = 0, masks_after = 0;
  int64_t newest = -1;
  const bool reached = t.receiveUntil([&](const Message& m) {
    const auto* silhouettes = std::get_if<SilhouettesData>(&m.body);
    if (!silhouettes) return false;
    newest = std::max(newest, m.frame_id);
    (m.frame_id < kDiesAt ? masks_before : masks_after) = silhouettes->masks.size();
    return newest >= kDiesAt + 40;
  });
  EXPECT_TRUE(reached) << "the node's silhouettes stopped after frame " << newest;
  EXPECT_EQ(masks_before, t.cameras.size());
  EXPECT_EQ(masks_after, t.cameras.size() - 1);
}

// Another thread asking for the cameras' health (the heartbeat's, the monitor's) while the capture
// thread waits in the source for frames gets it once the wait under way ends: the capture thread
// used to take the source again at once, and the heartbeat waited 22-29 ms on average, up to
// 150 ms, while the network thread sent nothing. Counted in the source's waits, not timed.
TEST(CameraNode, TheCamerasHealthIsNotKeptWaitingByTheCaptureThread) {
  WaitingSource* source = nullptr;
  NodeUnderTest t([&](const Rig& rig, std::vector<int> cameras) {
    auto made = std::make_unique<WaitingSource>(rig, std::move(cameras));
    source = made.get();
    return made;
  });
  ASSERT_TRUE(t.receiveUntil([](const Message& m) {
    return std::holds_alternative<SilhouettesData>(m.body);
  })) << "no silhouettes: the capture thread is not running";
  int64_t most = 0;
  for (int k = 0; k < 20; ++k) {
    std::this_thread::sleep_for(milliseconds(7));  // anywhere in the capture thread's waits
    const int64_t before = source->calls();
    const CameraNode::MonitorState state = t.node.monitorState();
    EXPECT_EQ(state.stats.size(), t.cameras.size());
    most = std::max(most, source->callsAtHealth() - before);
  }
  // The wait under way, and at most one begun as the health was asked for.
  EXPECT_LE(most, 2) << "the capture thread went on waiting in the source while the health waited";
}

// Every camera of the node reopened after a power cut counts from 0 again: the node keeps answering
// the studio's poses with its statistics for the new frames. (It kept the old frames' sets, whose
// ids were higher, and dropped each new one as it came: no statistics ever again.)
TEST(CameraNode, CamerasThatCountFromZeroAgainAreFollowed) {
  static constexpr int64_t kRestartAt = 2 * kFrameIdWindow;
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), -1, 0, 0, kRestartAt);
  });
  PoseData pose;
  pose.angles.assign(3 * kHumanJointCount, 0.0f);
  int64_t newest = -1;
  bool restarted = false;
  const bool answered = t.receiveUntil([&](const Message& m) {
    if (std::get_if<SilhouettesData>(&m.body)) {
      restarted = restarted || m.frame_id < newest - kFrameIdWindow;
      newest = std::max(newest, m.frame_id);
      Message answer;
      answer.frame_id = m.frame_id;
      answer.body = pose;
      t.studio.send(t.rig.nodes().front().name, answer, milliseconds(100));
      return false;
    }
    return restarted && std::get_if<VertexStatisticsData>(&m.body) && m.frame_id < kRestartAt / 2;
  });
  EXPECT_TRUE(restarted) << "the cameras never counted from 0 again";
  EXPECT_TRUE(answered) << "no statistics for a frame after the cameras counted from 0 again";
}

// A view looking at the stage's centre from 4 m, `width` x `height`.
ViewData viewOfSize(int width, int height) {
  ViewData view{0,  width, height, 0.8f * width, 0.8f * width, 0.5f * width, 0.5f * height,
                {}, {},    {}};
  view.rotation = {0, 1, 0, 0, 0, -1, -1, 0, 0};  // looking along -x, z up
  view.translation = {0, 1, 4};
  return view;
}

// The view changes (a director drags it) while a frame is refined: the frame is rendered with the
// view that came with its pose, not with the next frame's. The nodes' images of one frame were
// drawn from different views, which the studio blended into doubled edges, or refused for their
// size.
TEST(CameraNode, AFrameIsRenderedWithTheViewThatCameWithItsPose) {
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), -1, 0);
  });
  const std::string node = t.rig.nodes().front().name;
  const auto sendTo = [&](int64_t frame_id, MessageBody body) {
    Message m;
    m.frame_id = frame_id;
    m.body = std::move(body);
    return t.studio.send(node, m, milliseconds(100));
  };
  PoseData pose;
  pose.angles.assign(3 * kHumanJointCount, 0.0f);
  // A frame past the screens' learning, posed: its statistics come. The node keeps the last
  // frames_kept sets for their poses; on a loaded machine the source may have run past this one
  // before its pose came, so a later frame is tried then.
  int64_t frame = 39;
  bool refined = false;
  for (int attempt = 0; attempt < 5 && !refined; ++attempt) {
    ASSERT_TRUE(t.receiveUntil([&](const Message& m) {
      if (!std::get_if<SilhouettesData>(&m.body) || m.frame_id <= frame) return false;
      frame = m.frame_id;
      return true;
    }));
    ASSERT_TRUE(sendTo(frame, viewOfSize(160, 120)));
    ASSERT_TRUE(sendTo(frame, pose));
    refined = t.receiveUntil(
        [&](const Message& m) {
          return std::get_if<VertexStatisticsData>(&m.body) && m.frame_id == frame;
        },
        std::chrono::seconds(5));
  }
  ASSERT_TRUE(refined);
  // The next frame's view (larger) and pose reach the node before this frame's offsets.
  ASSERT_TRUE(sendTo(frame + 1, viewOfSize(320, 240)));
  ASSERT_TRUE(sendTo(frame + 1, pose));
  const RefineConfig refine;
  OffsetsData offsets;
  offsets.offset_count = refine.offsetLevels();
  offsets.offsets.assign(size_t(loadGenericHuman().rest.vertexCount()),
                         uint8_t(refine.zeroLevel()));
  ASSERT_TRUE(sendTo(frame, offsets));
  int width = 0;
  ASSERT_TRUE(t.receiveUntil([&](const Message& m) {
    const auto* image = std::get_if<PartialImageData>(&m.body);
    if (!image || m.frame_id != frame) return false;
    width = image->width;
    return true;
  }));
  EXPECT_EQ(width, 160);
}

// Lens caps on while the node learns the screens: every camera is said to see no screen; the
// caps off, the screens are learnt after all and the warnings go from the cameras' health.
// How many of a heartbeat's cameras show `warning` (-1: not a heartbeat).
int screenWarnings(const Message& m, const std::string& warning) {
  const auto* h = std::get_if<HeartbeatData>(&m.body);
  if (!h) return -1;
  int n = 0;
  for (const CameraHealthData& c : h->cameras) n += c.last_error.find(warning) != std::string::npos;
  return n;
}

TEST(CameraNode, AScreenThatCouldNotBeLearntIsLearntWhenItShows) {
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), -1, 0, /*dark_until=*/150);
  });
  const auto warnings = [](const Message& m) { return screenWarnings(m, "no green screen"); };
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
    return warnings(m) == int(t.cameras.size());
  })) << "no camera was said to see no screen";
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) { return warnings(m) == 0; }))
      << "the warnings stayed after the screens showed";
}

// The lights dim after the screens were learnt (a fader pulled, a lamp failing): every camera
// says so in its health while they are dim, and nothing once they are back.
TEST(CameraNode, AScreenThatDimsAfterLearningIsWarnedOf) {
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), -1, 0, 0, -1,
                                            /*dim_from=*/300, /*dim_until=*/800);
  });
  const auto dim = [](const Message& m) { return screenWarnings(m, "green screen too dim"); };
  int64_t newest = -1;
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
    if (std::holds_alternative<SilhouettesData>(m.body)) newest = m.frame_id;
    return newest >= 100 && dim(m) == 0;
  })) << "the screens were not learnt clean";
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) { return dim(m) == int(t.cameras.size()); }))
      << "no camera was said to see its screen dimmed";
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) { return dim(m) == 0; }))
      << "the warnings stayed after the lights came back";
}

// Told by the studio that its cameras count other ids than the other nodes' for the same instants,
// a node moves its frame ids by the shift from then on.
// A stage without a green screen, live: a room of many colours (no green to key), empty for the
// first 30 frames, then with the actor (a block of another colour) in the middle of every view.
class RoomSource : public FrameSource {
 public:
  RoomSource(Rig rig, std::vector<int> cameras)
      : rig_(std::move(rig)), cameras_(std::move(cameras)) {}
  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, milliseconds) override {
    const int camera = cameras_[next_ % cameras_.size()];
    const int64_t id = int64_t(next_ / cameras_.size());
    ++next_;
    if (next_ % cameras_.size() == 0) std::this_thread::sleep_for(milliseconds(5));
    frame.camera = camera;
    frame.frame_id = id;
    frame.timestamp_ns = id * 33'333'333;
    const Camera& c = rig_.camera(camera);
    frame.image.resize(PixelFormat::kRgb8, c.width(), c.height());
    for (int y = 0; y < c.height(); ++y) {
      for (int x = 0; x < c.width(); ++x) {
        uint8_t* p = &frame.image.pixels[3 * (size_t(y) * c.width() + x)];
        const bool actor = id >= kEmptyFrames && isActor(c, x, y);
        // Wallpaper: stripes of red, grey and blue, with a pixel of noise.
        const uint8_t noise = uint8_t((x * 7 + y * 13 + id) % 3);
        const uint8_t wall[3][3] = {{170, 60, 50}, {120, 120, 120}, {50, 70, 160}};
        const uint8_t* colour = wall[(x / 6 + y / 9) % 3];
        for (int k = 0; k < 3; ++k)
          p[k] = actor ? uint8_t(230 - k * 40) : uint8_t(colour[k] + noise);
      }
    }
    return true;
  }
  CameraStats stats(int) const override { return {}; }
  static bool isActor(const Camera& c, int x, int y) {
    return std::abs(x - c.width() / 2) < c.width() / 8 &&
           std::abs(y - c.height() / 2) < c.height() / 4;
  }
  static constexpr int64_t kEmptyFrames = 30;

 private:
  Rig rig_;
  std::vector<int> cameras_;
  size_t next_ = 0;
};

// Told to learn its clean plates from its first 20 sets (`lumistage-node --plate-frames 20`), a
// node shows nobody while it learns, then keys the actor on the plate where no green key could,
// every cell right, and says in its health that its cameras are keyed on their plates. Every
// fourth frame the silhouettes carry the actor's colour in each of his cells.
TEST(CameraNode, ALiveRigWithoutAGreenScreenIsKeyedOnThePlateItLearntFirst) {
  CameraNodeOptions options;
  options.plate_frames = 20;
  NodeUnderTest t(
      [](const Rig& rig, std::vector<int> cameras) {
        return std::make_unique<RoomSource>(rig, std::move(cameras));
      },
      options);
  int64_t empty_checked = 0, actor_checked = 0, coloured_checked = 0;
  bool said_plate = false;
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
    if (const auto* h = std::get_if<HeartbeatData>(&m.body)) {
      said_plate = !h->cameras.empty();
      for (const CameraHealthData& c : h->cameras)
        said_plate = said_plate && c.key == kKeyedOnPlate;
    }
    const auto* silhouettes = std::get_if<SilhouettesData>(&m.body);
    if (!silhouettes) return false;
    for (const SilhouetteMaskData& mask : silhouettes->masks) {
      const Camera& c = t.rig.camera(mask.camera);
      const int step = c.width() / mask.width;
      int wrong = 0, actor = 0;
      for (int y = 0; y < mask.height; ++y) {
        for (int x = 0; x < mask.width; ++x) {
          const size_t i = size_t(y) * mask.width + x;
          const bool keyed = (mask.bits[i / 8] >> (i % 8)) & 1;
          const bool truth = m.frame_id >= RoomSource::kEmptyFrames &&
                             RoomSource::isActor(c, x * step + step / 2, y * step + step / 2);
          wrong += keyed != truth;
          actor += truth;
        }
      }
      EXPECT_EQ(wrong, 0) << "frame " << m.frame_id << ", camera " << c.name();
      if (m.frame_id < RoomSource::kEmptyFrames) ++empty_checked;
      if (actor > 0) ++actor_checked;
      // The actor's colour in each of his cells, every kColourEveryFrames-th frame.
      if (wrong == 0 && actor > 0 && m.frame_id % kColourEveryFrames == 0) {
        ++coloured_checked;
        EXPECT_EQ(mask.colours.size(), size_t(3 * actor)) << "frame " << m.frame_id;
        // A cell wholly on the actor has his colour (one on his edge, a mean with the wall's).
        int off = 0;
        size_t k = 0;
        for (int y = 0; y < mask.height; ++y) {
          for (int x = 0; x < mask.width; ++x) {
            const size_t i = size_t(y) * mask.width + x;
            if (!((mask.bits[i / 8] >> (i % 8)) & 1) || k + 2 >= mask.colours.size()) continue;
            const uint8_t* rgb = &mask.colours[k];
            k += 3;
            const bool inside = RoomSource::isActor(c, x * step, y * step) &&
                                RoomSource::isActor(c, x * step + step - 1, y * step + step - 1);
            off += inside && (rgb[0] != 230 || rgb[1] != 190 || rgb[2] != 150);
          }
        }
        EXPECT_EQ(off, 0) << "frame " << m.frame_id;
      } else if (m.frame_id % kColourEveryFrames != 0) {
        EXPECT_TRUE(mask.colours.empty()) << "frame " << m.frame_id;
      }
    }
    return actor_checked > 20 && said_plate;
  })) << actor_checked
      << " silhouettes of the actor checked, keyed on the plate said: " << said_plate;
  EXPECT_GT(empty_checked, 10);
  EXPECT_GT(coloured_checked, 2);
}

TEST(CameraNode, ANodeMovesItsFrameIdsWhenTheStudioSaysTheyLieElsewhere) {
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<ScriptedSource>(rig, std::move(cameras), -1, 0);
  });
  std::string peer;
  int64_t before = -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (peer.empty() && std::chrono::steady_clock::now() < deadline) {
    const std::optional<ReceivedMessage> in = t.studio.receive(milliseconds(100));
    if (in && in->result.ok() &&
        std::holds_alternative<SilhouettesData>(in->result.message->body)) {
      peer = in->peer;
      before = in->result.message->frame_id;
    }
  }
  ASSERT_FALSE(peer.empty()) << "no silhouettes";
  Message shift;
  shift.sender = "studio";
  // A shift that would take its ids below 0 (a confused or hostile studio) is refused.
  shift.body = FrameIdsData{-1'000'000'000};
  ASSERT_TRUE(t.studio.send(peer, shift, milliseconds(1000)));
  shift.body = FrameIdsData{100000};
  ASSERT_TRUE(t.studio.send(peer, shift, milliseconds(1000)));
  bool negative = false;
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
    if (!std::holds_alternative<SilhouettesData>(m.body)) return false;
    negative = negative || m.frame_id < 0;
    return m.frame_id >= 100000 + before;
  })) << "the node's frame ids did not move";
  EXPECT_FALSE(negative);
}

// One camera's frames come 8 sets late for a while (its node's PC loaded): its node's sets go out
// without them, as before, but the take the studio asked for still gets every set whole. (The
// take recorded whole sets only: the late stretch was missing from it, and from the merged take of
// the whole rig.) The late camera is the last to deliver each set: once it keeps up it is awaited
// again (its late frames counted as delivered), not left out for good.
TEST(CameraNode, ATakeKeepsTheSetsACameraWasLateFor) {
  static constexpr int64_t kLateFrom = 150, kLateUntil = 200, kFirst = 100, kLast = 250;
  const std::filesystem::path folder = testing::testFolder("late_camera");
  CameraNodeOptions options;
  options.takes = folder;
  options.fps = 30;
  std::string peer;
  size_t masks_late = 0, masks_on_time = 0;
  {
    NodeUnderTest t(
        [](const Rig& rig, std::vector<int> cameras) {
          const int late = cameras.back();
          return std::make_unique<LateCameraSource>(rig, std::move(cameras), late, kLateFrom,
                                                    kLateUntil, 8);
        },
        options);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (peer.empty() && std::chrono::steady_clock::now() < deadline) {
      const std::optional<ReceivedMessage> in = t.studio.receive(milliseconds(100));
      if (in && in->result.ok() &&
          std::holds_alternative<SilhouettesData>(in->result.message->body))
        peer = in->peer;
    }
    ASSERT_FALSE(peer.empty()) << "no silhouettes";
    Message record;
    record.sender = "studio";
    record.body = RecordData{"late", kFirst, kLast};
    ASSERT_TRUE(t.studio.send(peer, record, milliseconds(1000)));
    EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
      const auto* silhouettes = std::get_if<SilhouettesData>(&m.body);
      if (!silhouettes) return false;
      if (m.frame_id == kLateFrom + 20) masks_late = silhouettes->masks.size();
      if (m.frame_id == kLateUntil + 20) masks_on_time = silhouettes->masks.size();
      return m.frame_id >= kLast + 30;
    }));
  }  // the node stops, its take written out
  EXPECT_EQ(masks_late, testing::smallRing().nodes().front().cameras.size() - 1)
      << "the sets waited for the late camera";
  EXPECT_EQ(masks_on_time, testing::smallRing().nodes().front().cameras.size());
  const SessionReader take(folder / "late" / testing::smallRing().nodes().front().name);
  ASSERT_EQ(take.frameCount(), kLast - kFirst + 1);
  for (int i = 0; i < take.frameCount(); ++i) ASSERT_EQ(take.frameId(i), kFirst + i);
  // The late camera's images are its own frames' (the source marks each frame's blue by its id).
  std::vector<CameraFrame> frames;
  take.readFrame(int(kLateFrom + 10 - kFirst), frames);
  for (const CameraFrame& f : frames) {
    ASSERT_FALSE(f.image.pixels.empty());
    EXPECT_EQ(f.image.pixels[2], uint8_t(60 + (kLateFrom + 10) % 7));
  }
}

// A node that reads its cameras too slowly skips frames: the ids of its sets go up by 10. Its
// sets still wait for every camera. (Counted in ids, every camera after the first looked silent at
// each jump, and the sets went out with one camera in three.)
TEST(CameraNode, SetsWaitForEveryCameraWhenTheNodeSkipsFrames) {
  NodeUnderTest t([](const Rig& rig, std::vector<int> cameras) {
    return std::make_unique<LateCameraSource>(rig, std::move(cameras), -1, 0, 0, 0, 10);
  });
  size_t fewest = 99;
  int sets = 0;
  EXPECT_TRUE(t.receiveUntil([&](const Message& m) {
    const auto* silhouettes = std::get_if<SilhouettesData>(&m.body);
    if (!silhouettes || m.frame_id < 100) return false;
    fewest = std::min(fewest, silhouettes->masks.size());
    return ++sets >= 30;
  }));
  EXPECT_EQ(fewest, t.cameras.size());
}

}  // namespace
}  // namespace lumistage
