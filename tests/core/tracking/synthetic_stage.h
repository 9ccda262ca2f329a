#pragma once

// Low-resolution silhouettes of the virtual studio's actor for any pose, without rendering
// images: the posed actor mesh rasterised at the cells' centres (rasterizeSilhouette). Shared by
// the tracker's tests and benchmark.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/body/human_model.h"
#include "core/sim/studio_config.h"
#include "core/tracking/mesh_silhouette.h"
#include "core/tracking/pose_tracker.h"

namespace lumistage::testing {

struct SyntheticStage {
  explicit SyntheticStage(const std::string& studio_yaml, double height_scale = 0.0,
                          int actor_vertices = 3000)
      : SyntheticStage(scaled(loadStudioConfig(studio_yaml), height_scale), actor_vertices) {}
  // A studio config already made (a drawn stage's: drawStage).
  explicit SyntheticStage(StudioConfig studio, int actor_vertices = 3000)
      : config(std::move(studio)) {
    config.actor.target_vertices = actor_vertices;
    actor = makeHumanModel(config.actor);
    silhouettes.resize(config.rig.cameraCount());
  }

  // Silhouettes of `pose` in `cameras` (every camera when empty); the actor off stage when
  // `absent`. Fills `joints` with the actor's true joints.
  const std::vector<const LowResSilhouette*>& render(const Pose& pose,
                                                     const std::vector<int>& cameras = {},
                                                     bool absent = false) {
    actor.skeleton.skinningTransforms(pose, transforms);
    skinMesh(actor, transforms, positions, normals);
    actor.skeleton.jointPositions(pose, joints);
    pointers.clear();
    for (int c = 0; c < config.rig.cameraCount(); ++c) {
      bool use = cameras.empty();
      for (int k : cameras) use = use || k == c;
      if (!use) continue;
      if (absent) {
        rasterizeSilhouette(Eigen::Matrix3Xf(3, 0), {}, config.rig.camera(c), c, step,
                            silhouettes[c]);
      } else {
        rasterizeSilhouette(positions, actor.rest.triangles, config.rig.camera(c), c, step,
                            silhouettes[c]);
      }
      pointers.push_back(&silhouettes[c]);
    }
    return pointers;
  }

  // `studio` with its actor `height_scale` times 1.75 m tall (> 0), or as it is.
  static StudioConfig scaled(StudioConfig studio, double height_scale) {
    if (height_scale > 0) studio.actor.shape.height_m = 1.75 * height_scale;
    return studio;
  }

  int step = PoseTrackerOptions{}.silhouette_step;  // as the nodes send them
  StudioConfig config;
  SkinnedMesh actor;
  std::vector<LowResSilhouette> silhouettes;
  std::vector<const LowResSilhouette*> pointers;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  std::vector<Eigen::Vector3d> joints;
};

// Mean per-joint position error, metres.
inline double mpjpe(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (size_t j = 0; j < a.size(); ++j) sum += (a[j] - b[j]).norm();
  return a.empty() ? 0.0 : sum / a.size();
}

}  // namespace lumistage::testing
