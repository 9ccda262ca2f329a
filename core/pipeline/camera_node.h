#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/frame_source.h"
#include "core/imaging/keyer.h"
#include "core/net/transport.h"
#include "core/pipeline/silhouettes.h"

namespace lumistage {

struct CameraNodeOptions {
  int silhouette_step = 8;
  std::chrono::milliseconds heartbeat{250};
  int frames_kept = 8;  // frame sets kept for the later stages (poses arrive a few frames later)
};

// The node's part of every frame, on the PC that owns the cameras (see DESIGN.md §1):
// capture a set of its cameras' frames; key them at low resolution and send the silhouettes;
// when the studio's pose for that frame arrives, pose the generic human (linear blend skinning)
// and send, per vertex, the colour statistics of its cameras that see it (sums, sums of squares,
// how many see it, how many see it inside the silhouette) — what the studio's modules combine
// exactly across nodes. Heartbeats carry every camera's counters.
class CameraNode {
 public:
  CameraNode(const Rig& rig, const std::string& name, std::unique_ptr<FrameSource> source,
             NodeEndpointConfig endpoint, SkinnedMesh body, CameraNodeOptions options = {});

  // Runs until `stop` is set or the source ends.
  void run(const std::atomic<bool>& stop);

  int64_t setsSent() const { return sets_sent_; }
  int64_t bytesSent() const { return bytes_sent_; }

 private:
  void processSet(int64_t frame_id, int64_t captured_ns);
  void answerPose(const Message& message);
  bool send(Message message);

  Rig rig_;
  std::string name_;
  std::vector<int> cameras_;  // rig indices of this node's cameras
  std::unique_ptr<FrameSource> source_;
  NodeEndpoint endpoint_;
  SkinnedMesh body_;
  CameraNodeOptions options_;
  std::vector<GreenScreenKeyer> keyers_;  // per own camera
  // Frames of sets still being assembled or awaiting their pose: frame id -> per own camera.
  std::map<int64_t, std::vector<CameraFrame>> sets_;
  std::map<int64_t, int> arrived_;
  MessageEncoder encoder_;
  std::vector<Eigen::Affine3f> transforms_;
  Eigen::Matrix3Xf positions_, normals_;
  int64_t sets_sent_ = 0, bytes_sent_ = 0;
};

}  // namespace lumistage
