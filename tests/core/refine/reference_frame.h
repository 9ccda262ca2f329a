#pragma once

// Frame 20 of the reference virtual studio as the refinement's benchmarks and the hot-path tests
// take it: its 12 views as Bayer images (as GigE cameras deliver them), the generic human posed on
// the actor's true joints, and the sampler's inputs for a node's cameras.
#include <vector>

#include "core/base/resource_path.h"
#include "core/body/human_model.h"
#include "core/body/joint_pose_fit.h"
#include "core/refine/refinement_sampler.h"
#include "core/sim/virtual_studio.h"

namespace lumistage::testing {

struct ReferenceFrame {
  StudioConfig config;
  SkinnedMesh generic = loadGenericHuman();
  std::vector<Image> images;
  std::vector<GreenScreenKeyer> keyers;  // learnt from the images, or the default keys
  StudioFrame frame;
  JointPoseFit fit;
  Eigen::Matrix3Xf positions, normals;  // the generic human posed on the true joints

  // The reference studio with its actor at about 4000 vertices; `learn_screens`: the keyers learn
  // the screen from the frame, as nodes do.
  explicit ReferenceFrame(bool learn_screens)
      : config(loadStudioConfig(resourcePath("studio/reference.yaml"))) {
    config.actor.target_vertices = 4000;
    VirtualStudio virtual_studio(config, 30);
    virtual_studio.renderFrame(20, frame);
    const Rig& rig = config.rig;
    images.resize(rig.cameraCount());
    keyers.resize(rig.cameraCount());
    for (int c = 0; c < rig.cameraCount(); ++c) {
      rgbaToImage(frame.images[c].data(), rig.camera(c).width(), rig.camera(c).height(),
                  PixelFormat::kBayerRggb8, images[c]);
      if (learn_screens) keyers[c].learnScreen(images[c].view());
    }
    fit = fitPoseToJoints(generic.skeleton, frame.joints,
                          initialJointPoseFit(generic.skeleton, frame.joints));
    posedScaledMesh(generic, fit, positions, normals);
  }

  // The sampler's inputs: node `node`'s cameras.
  std::vector<SamplerCamera> camerasOf(int node) const {
    std::vector<SamplerCamera> out;
    for (int c : config.rig.nodes()[node].cameras)
      out.push_back({&config.rig.camera(c), images[c].view(), &keyers[c], nullptr});
    return out;
  }
};

}  // namespace lumistage::testing
