#pragma once

// The studio's side of a frame with its nodes played by the test over the real transport: a
// scripted node, studios of one or two of them, and what the tests read off the studio.

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "core/body/human_model.h"
#include "core/body/human_skeleton.h"
#include "core/geometry/ring_rig.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/posed_body.h"
#include "core/pipeline/studio_coordinator.h"
#include "core/refine/refinement_statistics.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage::testing {

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
inline std::unique_ptr<StudioCoordinator> twoCameraStudio(int cameras_per_node,
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
inline VertexStatisticsData statisticsMessage(const RefinementStatistics& stats,
                                              const RefineConfig& refine) {
  VertexStatisticsData message{uint32_t(stats.vertex_count), refine.offset_count, {}};
  encodeRefinementStatistics(stats, message.packed);
  return message;
}

// A node's image of `view`: one pixel drawn, fully weighted, of red level `red`.
inline PartialImageData onePixelImage(const ViewData& view, uint8_t red = 0) {
  PartialImageData image{view.view, view.width, view.height, ImageEncoding::kRawRgba,
                         std::vector<uint8_t>(size_t(view.width) * view.height * 4, 0)};
  image.data[0] = red, image.data[3] = 255;
  return image;
}

// Runs the studio until `frames` frames are done, for at most `slices` of 10 ms.
inline int64_t framesDoneAfter(StudioCoordinator& studio, int64_t frames, int slices) {
  for (int slice = 0; slice < slices && studio.framesDone() < frames; ++slice)
    studio.runFor(milliseconds(10));
  return studio.framesDone();
}

inline int64_t badMessagesOf(const StudioCoordinator& studio, const std::string& name) {
  for (const NodeReport& n : studio.report().nodes)
    if (n.name == name) return n.bad_messages;
  return -1;
}

// The next pose the studio sends `node`, for a frame at or after `frame_id`.
inline std::optional<int64_t> nextPoseFrame(ScriptedNode& node, StudioCoordinator& studio,
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

}  // namespace lumistage::testing
