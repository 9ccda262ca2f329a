// The camera node's capture side, in process, with a source the test controls and the studio's
// endpoint played by the test over the real transport.
#include "core/pipeline/camera_node.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "core/body/human_model.h"
#include "core/net/transport.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

using std::chrono::milliseconds;

// The frames of a node's cameras, every camera of every frame in turn (a screen-green image), a
// frame every 5 ms; from frame `dies_at` on, camera `dead` delivers nothing (unplugged).
class DyingCameraSource : public FrameSource {
 public:
  DyingCameraSource(Rig rig, std::vector<int> cameras, int dead, int64_t dies_at)
      : rig_(std::move(rig)), cameras_(std::move(cameras)), dead_(dead), dies_at_(dies_at) {}
  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, milliseconds) override {
    for (;;) {
      const int camera = cameras_[next_ % cameras_.size()];
      const int64_t id = int64_t(next_ / cameras_.size());
      ++next_;
      if (camera == dead_ && id >= dies_at_) continue;
      if (next_ % cameras_.size() == 0) std::this_thread::sleep_for(milliseconds(5));
      frame.camera = camera;
      frame.frame_id = id;
      frame.timestamp_ns = id * 33'333'333;
      const Camera& c = rig_.camera(camera);
      frame.image.resize(PixelFormat::kRgb8, c.width(), c.height());
      for (size_t p = 0; p + 2 < frame.image.pixels.size(); p += 3)
        frame.image.pixels[p] = 40, frame.image.pixels[p + 1] = 150, frame.image.pixels[p + 2] = 60;
      return true;
    }
  }
  CameraStats stats(int) const override { return {}; }

 private:
  Rig rig_;
  std::vector<int> cameras_;
  int dead_;
  int64_t dies_at_;
  size_t next_ = 0;
};

// One of a node's cameras stops delivering (its cable pulled): the node's sets go out with the
// others, whose silhouettes keep reaching the studio, instead of every set waiting for the dead
// camera and being dropped.
TEST(CameraNode, ACameraThatStopsDeliveringDoesNotSilenceItsNode) {
  const Rig rig = testing::smallRing();
  StudioEndpointConfig studio_config;
  studio_config.bind = "tcp://127.0.0.1:*";
  studio_config.security = TransportSecurity::kPlain;
  StudioEndpoint studio(studio_config);
  const std::string node_name = rig.nodes().front().name;
  const std::vector<int> cameras = rig.nodes().front().cameras;
  ASSERT_GE(cameras.size(), 2u);
  NodeEndpointConfig endpoint;
  endpoint.connect = studio.endpoint();
  endpoint.name = node_name;
  endpoint.security = TransportSecurity::kPlain;
  constexpr int64_t kDiesAt = 20;
  CameraNode node(rig, node_name,
                  std::make_unique<DyingCameraSource>(rig, cameras, cameras[1], kDiesAt), endpoint,
                  loadGenericHuman());
  std::atomic<bool> stop{false};
  std::thread running([&] { node.run(stop); });
  size_t masks_before = 0, masks_after = 0;
  int64_t newest = -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (newest < kDiesAt + 40 && std::chrono::steady_clock::now() < deadline) {
    const std::optional<ReceivedMessage> in = studio.receive(milliseconds(100));
    if (!in || !in->result.ok()) continue;
    const Message& m = *in->result.message;
    const auto* silhouettes = std::get_if<SilhouettesData>(&m.body);
    if (!silhouettes) continue;
    newest = std::max(newest, m.frame_id);
    (m.frame_id < kDiesAt ? masks_before : masks_after) = silhouettes->masks.size();
  }
  stop = true;
  running.join();
  EXPECT_GE(newest, kDiesAt + 40) << "the node's silhouettes stopped after its camera died";
  EXPECT_EQ(masks_before, cameras.size());
  EXPECT_EQ(masks_after, cameras.size() - 1);
}

}  // namespace
}  // namespace lumistage
