#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/geometry/camera.h"

namespace lumistage {

// A camera-node PC and the cameras it owns.
struct RigNode {
  std::string name;
  std::string host;          // where the node runs (name or address); empty: not yet assigned
  std::vector<int> cameras;  // indices into Rig::cameras()

  bool operator==(const RigNode&) const = default;
};

// The capture volume: an axis-aligned box of the world frame, metres (z up, the floor at z = 0).
// The tracker carves the visual hull inside it and looks for an actor nowhere else.
struct StageBox {
  Eigen::Vector3d lower = {-1.5, -1.5, 0.0}, upper = {1.5, 1.5, 2.4};
  Eigen::Vector3d size() const { return upper - lower; }
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= lower.array()).all() && (p.array() <= upper.array()).all();
  }
  bool operator==(const StageBox&) const = default;
};

// The calibrated cameras of a stage and the nodes that own them. Every camera belongs to exactly
// one node; names are unique.
class Rig {
 public:
  Rig() = default;
  // Throws std::invalid_argument naming the offending camera or node: duplicate or invalid names,
  // a node referring to a camera index out of range, a camera in no node or in two nodes.
  Rig(std::vector<Camera> cameras, std::vector<RigNode> nodes);

  const std::vector<Camera>& cameras() const { return cameras_; }
  const Camera& camera(int index) const { return cameras_.at(index); }
  int cameraCount() const { return static_cast<int>(cameras_.size()); }
  std::optional<int> findCamera(std::string_view name) const;

  const std::vector<RigNode>& nodes() const { return nodes_; }
  int nodeCount() const { return static_cast<int>(nodes_.size()); }
  std::optional<int> findNode(std::string_view name) const;
  int nodeOfCamera(int camera_index) const { return node_of_camera_.at(camera_index); }
  // The pixels of one image from each camera, or from each of `cameras` (indices): a frame set's
  // size at one byte a pixel.
  int64_t pixelsPerSet() const;
  int64_t pixelsPerSet(std::span<const int> cameras) const;

  // The stage box the rig file gives (docs/rig-file.md), if it gives one; stageVolume() in
  // core/geometry/stage_volume.h is what to use. setStage throws std::invalid_argument for a box
  // that is not finite, whose lower corner is not below its upper one in every axis, whose floor
  // (lower z) is not between -0.5 and 0.1 m, whose top is not 1.5 to 5 m high, or that is more
  // than 20 m a side.
  const std::optional<StageBox>& stage() const { return stage_; }
  void setStage(std::optional<StageBox> stage);

  bool operator==(const Rig&) const = default;

 private:
  std::vector<Camera> cameras_;
  std::optional<StageBox> stage_;
  std::vector<RigNode> nodes_;
  std::vector<int> node_of_camera_;
};

}  // namespace lumistage

namespace lumistage {

// Nodes named node1..nodeN for cameras that come without an assignment (imports, generated rigs):
// N = ceil(camera_count / cameras_per_node), camera i to node i mod N. Dealing in turn rather than
// in blocks gives every node cameras all around the stage, so each node's partial render covers
// the whole view and any virtual camera loads the nodes evenly.
std::vector<RigNode> dealCamerasToNodes(int camera_count, int cameras_per_node);

// The rig of one node: its cameras (in its order) and itself, as a session it records holds it.
// Throws std::invalid_argument when the rig has no such node.
Rig nodeRig(const Rig& rig, std::string_view node);

}  // namespace lumistage
