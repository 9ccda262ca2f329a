// Which cameras see each vertex: a known sphere seen by a ring of cameras.
#include "core/render/vertex_visibility.h"

#include <gtest/gtest.h>

#include "core/base/error.h"
#include "core/geometry/ring_rig.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

// Every camera sees the sphere's vertices that face it and none of those that face away (away
// from the rim, where the maps' low resolution decides); a vertex behind the cameras or outside
// their images is seen by none.
TEST(VertexVisibility, CamerasSeeTheSideOfASphereThatFacesThem) {
  const Rig rig = testing::smallRing(640, 480);
  ASSERT_EQ(rig.cameraCount(), 12);
  const Eigen::Vector3d centre(0, 0, 1.0);
  TriangleMesh sphere = testing::icosphere(centre, 0.3, 3);
  const int n = sphere.vertexCount();
  // Two vertices in no triangle: high above the stage (outside every image), and behind camera 0
  // (on the line from the sphere through it).
  Eigen::Matrix3Xf positions(3, n + 2);
  positions.leftCols(n) = sphere.positions;
  positions.col(n) = Eigen::Vector3f(0, 0, 30);
  positions.col(n + 1) = (2.5 * rig.camera(0).centre() - 1.5 * centre).cast<float>();
  VertexVisibility visibility;
  visibility.compute(rig, positions, sphere.triangles, 4, 0.02f);
  ASSERT_EQ(visibility.masks().size(), size_t(n + 2));
  int counted = 0, wrong = 0;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Eigen::Vector3f eye = rig.camera(c).centre().cast<float>();
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3f p = sphere.positions.col(v);
      const float facing = sphere.normals.col(v).dot((eye - p).normalized());
      if (std::abs(facing) < 0.5f) continue;
      ++counted;
      wrong += bool(visibility.masks()[v] & (1u << c)) != (facing > 0);
    }
  }
  EXPECT_GT(counted, 12 * 250);  // of 642 vertices a camera
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(visibility.masks()[n], 0);
  EXPECT_EQ(visibility.masks()[n + 1] & 1u, 0);  // behind camera 0
}

// A vertex hidden behind another surface is not seen; the same vertex alone is.
TEST(VertexVisibility, ASurfaceInFrontHidesWhatIsBehindIt) {
  const Rig rig = testing::smallRing(640, 480);
  const Eigen::Vector3d target(0, 0, 1.0);
  const Eigen::Vector3d eye = rig.camera(0).centre();
  const Eigen::Vector3d toward = (eye - target).normalized();
  // A ball half way to camera 0, and a point just behind the target on the same ray.
  const TriangleMesh ball = testing::icosphere(target + 0.5 * (eye - target), 0.15, 2);
  const int n = ball.vertexCount();
  Eigen::Matrix3Xf positions(3, n + 1);
  positions.leftCols(n) = ball.positions;
  positions.col(n) = (target - 0.1 * toward).cast<float>();
  VertexVisibility visibility;
  visibility.compute(rig, positions, ball.triangles, 4, 0.03f);
  EXPECT_EQ(visibility.masks()[n] & 1u, 0) << "hidden by the ball from camera 0";
  int opposite = 0;  // the camera across the ring
  for (int c = 1; c < rig.cameraCount(); ++c)
    if ((rig.camera(c).centre() - target).dot(toward) <
        (rig.camera(opposite).centre() - target).dot(toward))
      opposite = c;
  EXPECT_NE(visibility.masks()[n] & (1u << opposite), 0) << "seen from across the ring";
  std::vector<Eigen::Vector3i> none;
  visibility.compute(rig, positions, none, 4, 0.03f);
  EXPECT_NE(visibility.masks()[n] & 1u, 0) << "nothing in front of it";
}

// A rig twice the reference (24 cameras): every camera of the ring sees a point over the stage's
// centre, those past the sixteenth too.
TEST(VertexVisibility, ARigOfTwentyFourCamerasHasABitForEachCamera) {
  RingRigSpec spec;
  spec.cameras = 24;
  const Rig rig = makeRingRig(spec);
  VertexVisibility visibility;
  Eigen::Matrix3Xf positions(3, 1);
  positions.col(0) = Eigen::Vector3f(0, 0, 1.0f);
  visibility.compute(rig, positions, {}, 4, 0.03f);
  ASSERT_EQ(visibility.masks().size(), 1u);
  EXPECT_EQ(visibility.masks()[0], (CameraMask(1) << 24) - 1);
}

TEST(VertexVisibility, MoreCamerasThanMasksHoldAreRefused) {
  RingRigSpec spec;
  spec.cameras = VertexVisibility::kMaxCameras + 1;
  spec.cameras_per_node = 1;
  const Rig rig = makeRingRig(spec);
  VertexVisibility visibility;
  const Eigen::Matrix3Xf positions = Eigen::Matrix3Xf::Zero(3, 1);
  EXPECT_THROW(visibility.compute(rig, positions, {}, 4, 0.03f), Error);
}

}  // namespace
}  // namespace lumistage
