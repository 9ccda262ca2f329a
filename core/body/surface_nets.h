#pragma once

#include <Eigen/Geometry>
#include <functional>

#include "core/body/skinned_mesh.h"

namespace lumistage {

// Extracts the zero level set of a signed distance function (negative inside) as a closed
// triangle mesh, by surface nets: one vertex per grid cell the surface crosses, placed at the
// mean of the cell's edge crossings and then pulled onto the surface, and one quad per crossed
// grid edge. The bounds must enclose the surface with at least one cell to spare. Vertex count
// scales as area / cell². Normals come from the mesh.
TriangleMesh extractSurface(const std::function<float(const Eigen::Vector3f&)>& sdf,
                            const Eigen::AlignedBox3f& bounds, float cell_m);

}  // namespace lumistage
