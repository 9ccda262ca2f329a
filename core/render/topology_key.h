#pragma once

#include <Eigen/Core>
#include <cstring>
#include <span>
#include <vector>

namespace lumistage {

// The mesh topology something was built for (PhongSubdivision, DrawOrder), so that it is rebuilt
// only when a frame's triangles or vertex count differ: the same every frame of a capture.
class TopologyKey {
 public:
  // Whether `triangles` over `vertex_count` vertices differ from the last call's; remembers them.
  bool changed(int vertex_count, std::span<const Eigen::Vector3i> triangles) {
    if (vertex_count == vertex_count_ && triangles.size() == triangles_.size() &&
        (triangles.empty() || !std::memcmp(triangles.data(), triangles_.data(),
                                           triangles.size() * sizeof(Eigen::Vector3i))))
      return false;
    triangles_.assign(triangles.begin(), triangles.end());
    vertex_count_ = vertex_count;
    return true;
  }

 private:
  std::vector<Eigen::Vector3i> triangles_;
  int vertex_count_ = -1;
};

}  // namespace lumistage
