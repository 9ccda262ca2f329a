#pragma once

#include "core/body/skinned_mesh.h"
#include "core/geometry/camera.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

// The low-resolution silhouette a camera would key for a mesh: a cell is set when the mesh covers
// the pixel at its centre (the pixel computeSilhouette() keys). Triangles are rasterised in the
// cell grid after projecting their vertices with the camera's lens distortion; a vertex behind
// the camera drops its triangles. Cheap ground truth for tests and benchmarks of the tracker,
// without rendering images. `out`'s buffer is reused.
void rasterizeSilhouette(const Eigen::Matrix3Xf& positions,
                         const std::vector<Eigen::Vector3i>& triangles, const Camera& camera,
                         int camera_index, int step, LowResSilhouette& out);

}  // namespace lumistage
