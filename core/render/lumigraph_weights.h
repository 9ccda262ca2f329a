#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

namespace lumistage {

// Unstructured lumigraph blending weights (Buehler et al. 2001, as the paper uses them), per
// vertex and input camera. For a surface point p with normal n, seen from the desired camera's
// centre d, input camera i (centre c_i) gets
//   angle_i  = the angle between the rays p->d and p->c_i   (angular distance to the desired view)
//   facing_i = cos of the angle between n and p->c_i         (how squarely camera i sees p)
// Among the cameras that see p (visibility from depth maps) and face it more than
// `min_facing`, the k with the smallest angle are kept; with t the (k+1)-th smallest angle (or
// `max_angle_rad` when there are only k), each gets
//   w_i = (1 - angle_i / t) / max(angle_i, epsilon) * smoothstep(min_facing, 1, facing_i)
// and all others 0. The raw weights are what a node renders as alpha; normalised (divided by
// their sum over all cameras of all nodes) they blend. A desired camera on input camera i drives
// angle_i to 0 and w_i far above the rest: the blend reproduces that camera's image.
struct LumigraphWeightParams {
  int k = 4;                    // cameras blended per point (LumigraphParams::k)
  double min_facing = 0.1;      // cos of 84 degrees: grazing views are left out
  double max_angle_rad = 1.57;  // the threshold when fewer than k+1 cameras qualify
  double epsilon_rad = 1e-4;    // angles below this count as this (no division by zero)
};

// Raw (unnormalised) weights of every input camera for one point. `visible[i]` says whether
// camera i sees p (not occluded); `weights` is resized to the camera count.
void lumigraphWeights(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                      const Eigen::Vector3d& desired, std::span<const Eigen::Vector3d> cameras,
                      std::span<const bool> visible, const LumigraphWeightParams& params,
                      std::vector<double>& weights);

}  // namespace lumistage
