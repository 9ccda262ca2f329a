#include "core/render/orbit_view.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/geometry/ring_rig.h"
#include "tests/core/geometry/test_cameras.h"

namespace lumistage {
namespace {

TEST(OrbitView, LooksAtItsTargetFromItsEye) {
  OrbitView v = OrbitView::studioDefault();
  const Camera c = v.camera(320, 240);
  EXPECT_LT((c.centre() - Eigen::Vector3d(-3.2, -3.2, 1.7)).norm(), 1e-9);
  const std::optional<Eigen::Vector2d> p = c.project(v.target());
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->x(), 159.5, 1e-6);
  EXPECT_NEAR(p->y(), 119.5, 1e-6);
  // Upright: a point above the target is higher in the image (smaller y).
  const std::optional<Eigen::Vector2d> above = c.project(v.target() + Eigen::Vector3d(0, 0, 0.5));
  ASSERT_TRUE(above);
  EXPECT_LT(above->y(), p->y() - 10);
}

TEST(OrbitView, HalfATurnSeesTheOtherSide) {
  // The director drags the camera round to the actor's back: the eye ends up opposite.
  OrbitView v;
  v.set(M_PI / 2, 0.1, 4.0);  // in front of an actor facing +y
  const Eigen::Vector3d front = v.eye();
  v.dragOrbit(480, 0, 480);  // a full-height drag: ~180 degrees
  const Eigen::Vector3d back = v.eye();
  EXPECT_NEAR(front.y(), -back.y() + 2 * v.target().y(), 1e-6);
  EXPECT_LT(back.y(), -3.5);  // behind the actor (facing +y)
  EXPECT_NEAR((back - v.target()).norm(), 4.0, 1e-9);
  // The stage centre stays in the middle of the picture.
  const std::optional<Eigen::Vector2d> p = v.camera(200, 100).project(v.target());
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->x(), 99.5, 1e-6);
}

TEST(OrbitView, PitchIsClampedShortOfTheVertical) {
  OrbitView v;
  v.orbit(0, 10);
  EXPECT_DOUBLE_EQ(v.pitch(), OrbitView::kMaxPitch_rad);
  v.orbit(0, -20);
  EXPECT_DOUBLE_EQ(v.pitch(), -OrbitView::kMaxPitch_rad);
  EXPECT_NO_THROW(v.camera(64, 48));  // still a valid rotation
}

TEST(OrbitView, PanFollowsTheCursorAtTheTargetsDepth) {
  OrbitView v = OrbitView::studioDefault();
  const Camera before = v.camera(640, 480);
  const Eigen::Vector3d point = v.target();
  v.dragPan(50, -30, 480);  // drag right and up
  const std::optional<Eigen::Vector2d> p = v.camera(640, 480).project(point);
  ASSERT_TRUE(p);
  // The point that was under the cursor moved with it.
  EXPECT_NEAR(p->x(), 319.5 + 50, 0.5);
  EXPECT_NEAR(p->y(), 239.5 - 30, 0.5);
  EXPECT_NEAR((v.eye() - before.centre()).norm(), (v.target() - point).norm(), 1e-9);
}

TEST(OrbitView, ZoomChangesTheDistanceWithinLimits) {
  OrbitView v;
  const double d = v.distance();
  v.wheelZoom(1);
  EXPECT_NEAR(v.distance(), 0.9 * d, 1e-12);
  v.zoom(1e-6);
  EXPECT_DOUBLE_EQ(v.distance(), OrbitView::kMinDistance_m);
  v.zoom(1e6);
  EXPECT_DOUBLE_EQ(v.distance(), OrbitView::kMaxDistance_m);
}

TEST(OrbitView, SnapsToAnInputCamera) {
  // Snapped to each reference camera, the view sees the stage as that camera does (the ring's
  // cameras do not roll; the view's principal point is the image centre).
  const Rig rig = makeRingRig(RingRigSpec{});
  for (int i = 0; i < rig.cameraCount(); ++i) {
    const Camera& input = rig.camera(i);
    const OrbitView v = OrbitView::fromCamera(input);
    const Camera view = v.camera(input.width(), input.height());
    EXPECT_LT((view.centre() - input.centre()).norm(), 1e-6) << input.name();
    EXPECT_GT(view.viewingDirection().dot(input.viewingDirection()), 1 - 1e-9) << input.name();
    const Eigen::Vector3d stage(0.3, -0.2, 1.2);
    const auto a = view.project(stage);
    const auto b = input.project(stage);
    ASSERT_TRUE(a && b);
    EXPECT_LT((*a - *b).norm(), 0.02 * input.width()) << input.name();
  }
}

TEST(OrbitView, PoseRoundTripsThroughFromPose) {
  std::mt19937 rng(3);
  for (int i = 0; i < 20; ++i) {
    OrbitView v;
    std::uniform_real_distribution<double> u(-1, 1);
    v.setTarget(Eigen::Vector3d(u(rng), u(rng), 1 + 0.5 * u(rng)));
    v.set(3 * u(rng), 1.2 * u(rng), 3 + u(rng));
    const OrbitView w = OrbitView::fromPose(v.pose(), v.distance());
    EXPECT_LT((w.eye() - v.eye()).norm(), 1e-9);
    EXPECT_LT((w.target() - v.target()).norm(), 1e-9);
  }
}

TEST(OrbitView, ViewDataDescribesTheSameCamera) {
  const OrbitView v = OrbitView::studioDefault();
  const ViewData d = toViewData(v.pose(), 320, 240, 7);
  EXPECT_EQ(d.view, 7);
  EXPECT_EQ(d.width, 320);
  ASSERT_EQ(d.rotation.size(), 9u);
  ASSERT_EQ(d.translation.size(), 3u);
  const Camera c = v.camera(320, 240);
  Eigen::Matrix3d R;
  for (int k = 0; k < 9; ++k) R(k / 3, k % 3) = d.rotation[k];
  const Eigen::Vector3d t(d.translation[0], d.translation[1], d.translation[2]);
  const Eigen::Vector3d x(0.2, 0.1, 1.0);
  const Eigen::Vector3d xc = R * x + t;
  EXPECT_NEAR(d.fx * xc.x() / xc.z() + d.cx, c.project(x)->x(), 1e-3);
  EXPECT_NEAR(d.fy * xc.y() / xc.z() + d.cy, c.project(x)->y(), 1e-3);
}

}  // namespace
}  // namespace lumistage
