#include "core/render/clone_set.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/net/message_codec.h"
#include "core/render/orbit_view.h"

namespace lumistage {
namespace {

TEST(CloneSet, AddsMovesTurnsAndRemoves) {
  CloneSet set;
  const int a = set.add({1, 0});
  const int b = set.add({-1, 0}, M_PI);
  EXPECT_NE(a, b);
  ASSERT_EQ(set.clones().size(), 2u);
  EXPECT_TRUE(set.moveBy(a, {0.5, 0.5}));
  EXPECT_TRUE(set.rotateBy(a, M_PI / 2));
  const Eigen::Vector3d moved = set.find(a)->transform() * Eigen::Vector3d(1, 0, 1);
  // Turned a quarter about the vertical through the origin, then shifted to (1.5, 0.5).
  EXPECT_LT((moved - Eigen::Vector3d(1.5, 1.5, 1)).norm(), 1e-12);
  EXPECT_TRUE(set.moveTo(b, {2, 2}));
  EXPECT_LT((set.find(b)->transform().translation() - Eigen::Vector3d(2, 2, 0)).norm(), 1e-12);
  EXPECT_TRUE(set.remove(a));
  EXPECT_FALSE(set.remove(a));
  EXPECT_FALSE(set.moveBy(a, {1, 1}));
  ASSERT_EQ(set.transforms().size(), 1u);
  EXPECT_EQ(set.add({0, 0}), b + 1);  // ids are never reused
}

// No edit leaves the set beyond what the nodes take in a view (they would refuse every view and
// the director's picture would freeze): 64 clones, offsets within 20 m; and every view of them
// is one the nodes decode.
TEST(CloneSet, StaysWithinWhatTheNodesTake) {
  CloneSet set;
  const int far = set.add({5000, -0.5});
  EXPECT_EQ(set.find(far)->offset_m, Eigen::Vector2d(CloneSet::kReachM, -0.5));
  EXPECT_TRUE(set.moveBy(far, {0, -1e9}));  // a drag toward the horizon
  EXPECT_EQ(set.find(far)->offset_m, Eigen::Vector2d(CloneSet::kReachM, -CloneSet::kReachM));
  EXPECT_TRUE(set.moveTo(far, {std::nan(""), 1}));
  EXPECT_EQ(set.find(far)->offset_m, Eigen::Vector2d(0, 1));
  while (int(set.clones().size()) < CloneSet::kMaxClones) ASSERT_GT(set.add({1, 1}), 0);
  EXPECT_EQ(set.add({1, 1}), 0);
  EXPECT_EQ(int(set.clones().size()), CloneSet::kMaxClones);
  EXPECT_EQ(CloneSet::kMaxClones, MessageLimits{}.max_clones);

  Message message;
  message.sender = "studio";
  ViewData view{0, 320, 240, 300, 300, 160, 120, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 3}, {}};
  set.moveBy(far, {-1e9, 1e9});
  for (const Clone& c : set.clones())
    view.clones.insert(view.clones.end(),
                       {float(c.offset_m.x()), float(c.offset_m.y()), float(c.yaw_rad)});
  message.body = view;
  const std::vector<uint8_t> bytes = encodeMessage(message);
  const DecodeResult decoded = decodeMessage(bytes.data(), bytes.size());
  EXPECT_TRUE(decoded.ok()) << decoded.error();
}

TEST(CloneSet, TurnsAboutThePivot) {
  CloneSet set;
  const int id = set.add({1, 0}, M_PI);
  const Eigen::Vector3d actor(2, 1, 0);
  const Eigen::Affine3d t = set.find(id)->transform(actor);
  // The actor's own place goes to its place shifted; a point ahead of it turns about it.
  EXPECT_LT((t * actor - Eigen::Vector3d(3, 1, 0)).norm(), 1e-12);
  EXPECT_LT((t * Eigen::Vector3d(2, 2, 1.5) - Eigen::Vector3d(3, 0, 1.5)).norm(), 1e-12);
}

TEST(CloneSet, PicksTheCloneUnderTheCursor) {
  CloneSet set;
  const int left = set.add({0, -1});
  const int right = set.add({0, 1});
  OrbitView v;
  v.set(0, 0.3, 5);  // from +x, looking at the origin
  const Camera view = v.camera(640, 480);
  const Eigen::Vector3d actor(0, 0, 0);
  const auto p = view.project(set.find(right)->transform() * actor);
  ASSERT_TRUE(p);
  EXPECT_EQ(set.pick(view, *p + Eigen::Vector2d(3, 2), actor), right);
  EXPECT_EQ(set.pick(view, *view.project(Eigen::Vector3d(0, -1, 0)), actor), left);
  EXPECT_FALSE(set.pick(view, Eigen::Vector2d(5, 5), actor));
}

TEST(CloneSet, FloorPointUnderARay) {
  const auto p = floorPoint({Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(1, 0, -1).normalized()});
  ASSERT_TRUE(p);
  EXPECT_LT((*p - Eigen::Vector3d(2, 0, 0)).norm(), 1e-12);
  EXPECT_FALSE(floorPoint({Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(0, 0, 1)}));
}

}  // namespace
}  // namespace lumistage
