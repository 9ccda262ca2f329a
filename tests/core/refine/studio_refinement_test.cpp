// The refinement on the virtual studio: the generic human, posed to the actor's true joints,
// refined from the rendered images, comes closer to the actor's true surface.
#include <gtest/gtest.h>

#include "core/body/human_model.h"
#include "core/body/joint_pose_fit.h"
#include "core/eval/surface_metrics.h"
#include "core/refine/frame_refiner.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_sampler.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/sim/reference_studio.h"

namespace lumistage {
namespace {

TEST(StudioRefinement, RefinedWalkerIsMuchCloserToTheTrueSurface) {
  const StudioConfig config = testing::referenceStudio(4000);
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
    // The vertices and their window points (RefineConfig::window_points).
    combined.reset(config.refine.window_points * generic.rest.vertexCount(),
                   config.refine.offset_count, config.refine.colour_bits);
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

// The strict leave-one-camera-out score refines without the scored camera: with it left out, its
// image has no say in the refined mesh (a ruined image changes nothing); sampled, it does.
TEST(StudioRefinement, FrameRefinerLeavesTheLeftOutCameraUnsampled) {
  const StudioConfig config = testing::referenceStudio(3000);
  VirtualStudio studio(config, 20);
  const Rig& rig = studio.rig();
  const SkinnedMesh generic = loadGenericHuman();
  StudioFrame frame;
  studio.renderFrame(10, frame);
  std::vector<CameraFrame> frames(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    frames[c].camera = c;
    rgbaToImage(frame.images[c].data(), rig.camera(c).width(), rig.camera(c).height(),
                PixelFormat::kRgb8, frames[c].image);
  }
  const JointPoseFit fit = fitPoseToJoints(generic.skeleton, frame.joints,
                                           initialJointPoseFit(generic.skeleton, frame.joints));
  Eigen::Matrix3Xf positions, normals;
  posedScaledMesh(generic, fit, positions, normals);
  const auto refined = [&](int left_out) {
    FrameRefiner refiner(rig, config.refine, generic.rest.vertexCount(), generic.rest.triangles);
    Eigen::Matrix3Xf out;
    refiner.refine(frames, positions, normals, out, left_out);
    return out;
  };
  const int c = 4;
  const Eigen::Matrix3Xf left_out = refined(c), sampled = refined(-1);
  // The actor's half of camera c's image turned to screen green, as if nobody stood there.
  std::vector<uint8_t>& pixels = frames[c].image.pixels;
  for (size_t p = 0; p < pixels.size(); p += 3) {
    if (frame.masks[c][p / 3] == 0) continue;
    pixels[p] = 40;
    pixels[p + 1] = 150;
    pixels[p + 2] = 60;
  }
  EXPECT_EQ(refined(c), left_out);
  const Eigen::Matrix3Xf ruined = refined(-1);
  int moved = 0;
  for (int v = 0; v < ruined.cols(); ++v) moved += (ruined.col(v) - sampled.col(v)).norm() > 1e-4f;
  EXPECT_GT(moved, 100) << "camera " << c << "'s image does not shape the refinement";
}

}  // namespace
}  // namespace lumistage
