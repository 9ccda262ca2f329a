#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/calib/wand_session.h"
#include "core/capture/image.h"
#include "core/geometry/rig.h"

namespace lumistage {

// A wand session simulated geometrically through a known rig: the wand's bright point follows a
// smooth random path through the stage volume (as a technician waves it), is projected through
// every camera with its lens distortion, gets Gaussian pixel noise, and is dropped where it falls
// outside an image or behind a camera, or (dropout) where the technician's body hides it. An
// outlier replaces an observation by a random pixel (a reflection, a stray light).
struct WandSimulationOptions {
  int samples = 1000;
  double noise_px = 0.3;           // standard deviation of each pixel coordinate
  double outlier_fraction = 0.05;  // of the observations
  double dropout = 0.1;            // chance that a camera misses a sample it could see
  Eigen::Vector3d volume_min_m = {-1.3, -1.3, 0.2};
  Eigen::Vector3d volume_max_m = {1.3, 1.3, 2.1};
  double step_m = 0.08;  // typical distance between consecutive samples
  // > 0: every sample gets a partner at this distance (the wand's other LED, lit in turn), and
  // the pairs are listed in the session.
  double wand_length_m = 0;
  // Floor marks at these world points (the wand held on marks on the floor), noise but no
  // outliers. Default: the origin, 1 m along x, 1 m along y.
  std::vector<Eigen::Vector3d> floor_marks_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  uint32_t seed = 1;
};

struct SimulatedWandSession {
  WandSession session;
  std::vector<Eigen::Vector3d> points_m;      // true world position of each sample
  std::vector<std::vector<uint8_t>> outlier;  // [sample][camera]: observation is an outlier
};

SimulatedWandSession simulateWandSession(const Rig& rig, const WandSimulationOptions& options);

// A camera's mono8 frame of the dark stage (level 10) with bright spots (the wand's LED where the
// lens puts it, reflections): Gaussian, 2 px standard deviation, peak 250. Reuses `out`.
void renderWandFrame(const Camera& camera, const std::vector<Eigen::Vector2d>& spots_px,
                     Image& out);

}  // namespace lumistage
