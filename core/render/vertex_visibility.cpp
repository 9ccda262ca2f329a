#include "core/render/vertex_visibility.h"

#include <string>

#include "core/base/error.h"

namespace lumistage {

void VertexVisibility::compute(const Rig& rig, const Eigen::Matrix3Xf& positions,
                               std::span<const Eigen::Vector3i> triangles, int divisor,
                               float tolerance_m) {
  const int cameras = rig.cameraCount();
  if (cameras > kMaxCameras)
    throw Error("VertexVisibility: the rig has " + std::to_string(cameras) + " cameras; at most " +
                std::to_string(kMaxCameras) + " are supported");
  const int n = static_cast<int>(positions.cols());
  if (maps_.size() < size_t(cameras)) maps_.resize(cameras);
  masks_.assign(n, 0);
  for (int c = 0; c < cameras; ++c) {
    const Camera& camera = rig.camera(c);
    DepthMap& map = maps_[c];
    map.render(camera, positions, triangles, divisor);
    const Eigen::Matrix2Xf& pixels = map.vertexPixels();
    const Eigen::VectorXf& depths = map.vertexDepths();
    const float right = float(camera.width()) - 0.5f, bottom = float(camera.height()) - 0.5f;
    const CameraMask bit = CameraMask(1u) << c;
    for (int v = 0; v < n; ++v) {
      const float x = pixels(0, v), y = pixels(1, v), z = depths[v];
      if (!(z > 0.05f) || !(x >= -0.5f && x <= right && y >= -0.5f && y <= bottom)) continue;
      if (map.visible(x, y, z, tolerance_m)) masks_[v] |= bit;
    }
  }
}

}  // namespace lumistage
