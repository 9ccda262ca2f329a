#pragma once

#include "core/body/human_skeleton.h"
#include "core/body/skinned_mesh.h"

namespace lumistage::testing {

// The human skeleton with a small tetrahedron at every joint, half of it blended with the parent.
inline SkinnedMesh makeHumanMesh() {
  SkinnedMesh mesh;
  mesh.skeleton = makeHumanSkeleton();
  const int n = mesh.skeleton.jointCount();
  mesh.rest.positions.resize(3, 4 * n);
  const Eigen::Vector3f tetra[4] = {{0.03f, 0.03f, 0.03f},
                                    {0.03f, -0.03f, -0.03f},
                                    {-0.03f, 0.03f, -0.03f},
                                    {-0.03f, -0.03f, 0.03f}};
  for (int j = 0; j < n; ++j) {
    const int parent = mesh.skeleton.joint(j).parent;
    for (int k = 0; k < 4; ++k) {
      mesh.rest.positions.col(4 * j + k) =
          mesh.skeleton.restPositions()[j].cast<float>() + tetra[k];
      if (k < 2 || parent < 0) {
        mesh.skin.joints.push_back({static_cast<uint16_t>(j), 0, 0, 0});
        mesh.skin.weights.push_back({1, 0, 0, 0});
      } else {
        mesh.skin.joints.push_back({static_cast<uint16_t>(j), static_cast<uint16_t>(parent), 0, 0});
        mesh.skin.weights.push_back({0.6f, 0.4f, 0, 0});
      }
    }
    const int b = 4 * j;
    mesh.rest.triangles.emplace_back(b + 0, b + 1, b + 2);
    mesh.rest.triangles.emplace_back(b + 0, b + 3, b + 1);
    mesh.rest.triangles.emplace_back(b + 0, b + 2, b + 3);
    mesh.rest.triangles.emplace_back(b + 1, b + 3, b + 2);
  }
  mesh.rest.computeNormals();
  return mesh;
}

}  // namespace lumistage::testing
