// The refinement on the virtual studio: the generic human, posed to the actor's true joints,
// refined from the rendered images, comes closer to the actor's true surface.
#include <gtest/gtest.h>

#include "core/body/human_model.h"
#include "core/body/joint_pose_fit.h"
#include "core/eval/surface_metrics.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_sampler.h"
#include "core/sim/virtual_studio.h"

namespace lumistage {
namespace {

TEST(StudioRefinement, RefinedWalkerIsMuchCloserToTheTrueSurface) {
  StudioConfig config =
      loadStudioConfig(std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/studio/reference.yaml");
  config.actor.target_vertices = 4000;
  VirtualStudio studio(config, 40);
  const Rig& rig = studio.rig();
  const SkinnedMesh generic = loadGenericHuman();
  RefinementSampler sampler(config.refine);
  MeshRefiner refiner(config.refine, generic.rest.vertexCount(), generic.rest.triangles);
  StudioFrame frame;
  std::vector<Image> images(rig.cameraCount());
  std::vector<GreenScreenKeyer> keyers(rig.cameraCount());
  JointPoseFit fit;
  Eigen::Matrix3Xf positions, normals, refined;
  RefinementStatistics part, combined;
  std::vector<uint8_t> offsets;
  for (int f : {20, 21}) {
    studio.renderFrame(f, frame);
    for (int c = 0; c < rig.cameraCount(); ++c) {
      rgbaToImage(frame.images[c].data(), rig.camera(c).width(), rig.camera(c).height(),
                  PixelFormat::kBayerRggb8, images[c]);
    }
    fit = fitPoseToJoints(generic.skeleton, frame.joints,
                          f == 20 ? initialJointPoseFit(generic.skeleton, frame.joints) : fit);
    posedScaledMesh(generic, fit, positions, normals);
    combined.reset(generic.rest.vertexCount(), config.refine.offset_count,
                   config.refine.colour_bits);
    for (const RigNode& node : rig.nodes()) {
      std::vector<SamplerCamera> cameras;
      for (int c : node.cameras)
        cameras.push_back({&rig.camera(c), images[c].view(), &keyers[c], nullptr});
      sampler.sample(cameras, positions, normals, generic.rest.triangles, part);
      ASSERT_TRUE(combined.add(part));
    }
    ASSERT_TRUE(refiner.refine(combined, offsets));
    applyOffsets(config.refine, offsets, positions, normals, refined);
    const SurfaceDistance truth(frame.surface);
    const SurfaceError before = surfaceError(positions, truth),
                       after = surfaceError(refined, truth);
    EXPECT_LT(after.mean_mm, 0.5 * before.mean_mm)
        << "frame " << f << ": " << before.mean_mm << " mm -> " << after.mean_mm << " mm";
    EXPECT_LT(after.p95_mm, before.p95_mm) << "frame " << f;
  }
}

}  // namespace
}  // namespace lumistage
