#include "core/geometry/rig.h"

#include <fmt/format.h>

#include <stdexcept>
#include <unordered_set>

namespace lumistage {

Rig::Rig(std::vector<Camera> cameras, std::vector<RigNode> nodes)
    : cameras_(std::move(cameras)), nodes_(std::move(nodes)) {
  std::unordered_set<std::string> names;
  for (const Camera& camera : cameras_) {
    if (!names.insert(camera.name()).second) {
      throw std::invalid_argument("camera '" + camera.name() + "' is defined twice");
    }
  }
  names.clear();
  node_of_camera_.assign(cameras_.size(), -1);
  for (int n = 0; n < static_cast<int>(nodes_.size()); ++n) {
    const RigNode& node = nodes_[n];
    if (!isValidName(node.name)) {
      throw std::invalid_argument("node '" + node.name +
                                  "': invalid name: expected 1-64 characters of A-Z a-z 0-9 _ . -");
    }
    if (!names.insert(node.name).second) {
      throw std::invalid_argument("node '" + node.name + "' is defined twice");
    }
    for (int c : node.cameras) {
      if (c < 0 || c >= static_cast<int>(cameras_.size())) {
        throw std::invalid_argument("node '" + node.name + "' refers to camera index " +
                                    std::to_string(c) + ", but the rig has " +
                                    std::to_string(cameras_.size()) + " cameras");
      }
      if (node_of_camera_[c] >= 0) {
        throw std::invalid_argument("camera '" + cameras_[c].name() + "' belongs to both node '" +
                                    nodes_[node_of_camera_[c]].name + "' and node '" + node.name +
                                    "'");
      }
      node_of_camera_[c] = n;
      cameras_[c].setNode(node.name);
    }
  }
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (node_of_camera_[c] < 0) {
      throw std::invalid_argument("camera '" + cameras_[c].name() +
                                  "' belongs to no node; every camera must be listed by one node");
    }
  }
}

void Rig::setStage(std::optional<StageBox> stage) {
  if (stage) {
    const auto box = [&] {
      return fmt::format("[{}, {}, {}] to [{}, {}, {}]", stage->lower.x(), stage->lower.y(),
                         stage->lower.z(), stage->upper.x(), stage->upper.y(), stage->upper.z());
    };
    if (!stage->lower.allFinite() || !stage->upper.allFinite())
      throw std::invalid_argument("the stage box " + box() + ": expected finite numbers");
    if ((stage->lower.array() >= stage->upper.array()).any())
      throw std::invalid_argument("the stage box " + box() +
                                  ": expected the lower corner below the upper one in x, y and z");
    if (stage->lower.z() > 0.1 || stage->lower.z() < -0.5)
      throw std::invalid_argument("the stage box " + box() +
                                  ": expected its floor at the stage's (lower z between -0.5 and "
                                  "0.1 m): the actor stands on z = 0");
    if (stage->upper.z() < 1.5 || stage->upper.z() > 5)
      throw std::invalid_argument("the stage box " + box() +
                                  ": expected it 1.5 to 5 m high (upper z): an actor must fit");
    const Eigen::Vector3d size = stage->upper - stage->lower;
    if (size.x() > 20 || size.y() > 20)
      throw std::invalid_argument("the stage box " + box() +
                                  ": expected at most 20 m a side (metres: a rig in centimetres?)");
  }
  stage_ = std::move(stage);
}

std::optional<int> Rig::findCamera(std::string_view name) const {
  for (int i = 0; i < cameraCount(); ++i) {
    if (cameras_[i].name() == name) return i;
  }
  return std::nullopt;
}

std::optional<int> Rig::findNode(std::string_view name) const {
  for (int i = 0; i < nodeCount(); ++i) {
    if (nodes_[i].name == name) return i;
  }
  return std::nullopt;
}

int64_t Rig::pixelsPerSet() const {
  int64_t pixels = 0;
  for (const Camera& c : cameras_) pixels += int64_t(c.width()) * c.height();
  return pixels;
}

int64_t Rig::pixelsPerSet(std::span<const int> cameras) const {
  int64_t pixels = 0;
  for (int c : cameras) pixels += int64_t(camera(c).width()) * camera(c).height();
  return pixels;
}

}  // namespace lumistage

namespace lumistage {

std::vector<RigNode> dealCamerasToNodes(int camera_count, int cameras_per_node) {
  if (camera_count < 0 || cameras_per_node <= 0) {
    throw std::invalid_argument("cameras per node must be positive, got " +
                                std::to_string(cameras_per_node));
  }
  const int node_count = (camera_count + cameras_per_node - 1) / cameras_per_node;
  std::vector<RigNode> nodes(node_count);
  for (int n = 0; n < node_count; ++n) nodes[n].name = "node" + std::to_string(n + 1);
  for (int c = 0; c < camera_count; ++c) nodes[c % node_count].cameras.push_back(c);
  return nodes;
}

Rig nodeRig(const Rig& rig, std::string_view node) {
  const std::optional<int> index = rig.findNode(node);
  if (!index) throw std::invalid_argument("no node '" + std::string(node) + "' in the rig");
  RigNode part = rig.nodes()[*index];
  std::vector<Camera> cameras;
  for (int& c : part.cameras) {
    cameras.push_back(rig.camera(c));
    c = static_cast<int>(cameras.size()) - 1;
  }
  Rig out(std::move(cameras), {std::move(part)});
  out.setStage(rig.stage());
  return out;
}

}  // namespace lumistage
