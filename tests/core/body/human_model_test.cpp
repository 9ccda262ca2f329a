#include "core/body/human_model.h"

#include <gtest/gtest.h>

#include <limits>
#include <numbers>
#include <random>

#include "core/geometry/ring_rig.h"
#include "core/tracking/pose_tracker.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(HumanModel, GenericHumanIsClosedManifoldWithAbout2000Vertices) {
  const SkinnedMesh human = makeHumanModel();
  EXPECT_GT(human.rest.vertexCount(), 1800);
  EXPECT_LT(human.rest.vertexCount(), 2300);
  EXPECT_EQ(checkClosedManifold(human.rest).error(), "");
  // Closed and outward: the signed volume is positive and near a person's (~65 litres).
  double volume = 0;
  for (const Eigen::Vector3i& t : human.rest.triangles) {
    const Eigen::Vector3d a = human.rest.positions.col(t[0]).cast<double>();
    const Eigen::Vector3d b = human.rest.positions.col(t[1]).cast<double>();
    const Eigen::Vector3d c = human.rest.positions.col(t[2]).cast<double>();
    volume += a.dot(b.cross(c)) / 6;
  }
  EXPECT_GT(volume, 0.045);
  EXPECT_LT(volume, 0.1);
  // About 1.75 m tall, standing on the floor.
  EXPECT_NEAR(human.rest.positions.row(2).maxCoeff(), 1.75, 0.04);
  EXPECT_NEAR(human.rest.positions.row(2).minCoeff(), 0.0, 0.03);
}

TEST(HumanModel, WeightsAreSmoothAndLegsDoNotPullOnEachOther) {
  const SkinnedMesh human = makeHumanModel();
  human.validate();
  for (int v = 0; v < human.rest.vertexCount(); ++v) {
    const Eigen::Vector3f p = human.rest.positions.col(v);
    if (p.z() > 0.8f) continue;  // below the crotch: one leg only
    for (int k = 0; k < kMaxInfluences; ++k) {
      if (human.skin.weights[v][k] < 0.01f) continue;
      const int joint = human.skin.joints[v][k];
      const bool right_leg = joint >= kRightHip && joint <= kRightFoot;
      const bool left_leg = joint >= kLeftHip && joint <= kLeftFoot;
      if (p.x() > 0.03f) {
        EXPECT_FALSE(left_leg) << "vertex " << v;
      }
      if (p.x() < -0.03f) {
        EXPECT_FALSE(right_leg) << "vertex " << v;
      }
    }
  }
  // Posing the elbow moves the hand's vertices with the forearm and leaves the other arm alone.
  Pose pose = Pose::rest(human.skeleton.jointCount());
  pose.angles_rad[kRightElbow] = Eigen::Vector3d(0, 0, std::numbers::pi / 2);
  std::vector<Eigen::Affine3f> transforms;
  human.skeleton.skinningTransforms(pose, transforms);
  Eigen::Matrix3Xf posed, normals;
  skinMesh(human, transforms, posed, normals);
  const Eigen::Vector3f elbow = human.skeleton.restPositions()[kRightElbow].cast<float>();
  for (int v = 0; v < human.rest.vertexCount(); ++v) {
    const Eigen::Vector3f p = human.rest.positions.col(v);
    if (p.x() > elbow.x() + 0.12f) {  // forearm and hand: swung to point forward
      EXPECT_GT(posed(1, v), 0.08f) << "vertex " << v;
      EXPECT_LT(posed(0, v), elbow.x() + 0.1f) << "vertex " << v;
    }
    if (p.x() < 0) {
      EXPECT_LT((posed.col(v) - p).norm(), 1e-5f);
    }
  }
}

TEST(HumanModel, ActorDiffersFromTheGenericHuman) {
  HumanModelSpec actor;
  actor.shape.height_m = 1.82;
  actor.shape.girth_scale = 1.1;
  actor.clothing = true;
  actor.target_vertices = 6000;
  const SkinnedMesh m = makeHumanModel(actor);
  EXPECT_EQ(checkClosedManifold(m.rest).error(), "");
  EXPECT_NEAR(m.rest.positions.row(2).maxCoeff(), 1.82 + 0.01, 0.05);
  int counts[5] = {};
  for (uint8_t material : m.materials) ++counts[material];
  for (int material = 0; material < 5; ++material) EXPECT_GT(counts[material], 50) << material;
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

class ShippedGenericHuman : public ::testing::TestWithParam<BodyDetail> {};

TEST_P(ShippedGenericHuman, IsTheGeneratedOne) {
  // resources/body/generic_human.glb and generic_human_fine.glb are written by `lumistage body
  // generate [--vertices 4000]`; they must not drift.
  const SkinnedMesh shipped = loadGenericHuman(GetParam());
  HumanModelSpec spec;
  spec.target_vertices = bodyDetailVertices(GetParam());
  const SkinnedMesh generated = makeHumanModel(spec);
  ASSERT_EQ(shipped.rest.vertexCount(), generated.rest.vertexCount());
  ASSERT_EQ(shipped.skeleton.jointCount(), generated.skeleton.jointCount());
  EXPECT_EQ(checkClosedManifold(shipped.rest).error(), "");
  for (int j = 0; j < generated.skeleton.jointCount(); ++j) {
    EXPECT_EQ(shipped.skeleton.joint(j).name, generated.skeleton.joint(j).name);
    EXPECT_LT((shipped.skeleton.restPositions()[j] - generated.skeleton.restPositions()[j]).norm(),
              1e-5);
  }
  // Posed alike: every posed vertex of one has a twin in the other (order may differ).
  Pose pose = Pose::rest(generated.skeleton.jointCount());
  pose.angles_rad[kLeftElbow] = Eigen::Vector3d(0, 0, -1.0);
  pose.angles_rad[kRightHip] = Eigen::Vector3d(0.7, 0, 0);
  std::vector<Eigen::Affine3f> a_transforms, b_transforms;
  shipped.skeleton.skinningTransforms(pose, a_transforms);
  generated.skeleton.skinningTransforms(pose, b_transforms);
  Eigen::Matrix3Xf a, b, na, nb;
  skinMesh(shipped, a_transforms, a, na);
  skinMesh(generated, b_transforms, b, nb);
  float worst = 0;
  for (int v = 0; v < a.cols(); ++v) {
    worst = std::max(worst, std::sqrt((b.colwise() - a.col(v)).colwise().squaredNorm().minCoeff()));
  }
  EXPECT_LT(worst, 1e-4f);
}

INSTANTIATE_TEST_SUITE_P(HumanModel, ShippedGenericHuman,
                         ::testing::Values(BodyDetail::kStandard, BodyDetail::kFine),
                         [](const ::testing::TestParamInfo<BodyDetail>& info) {
                           return std::string(bodyDetailName(info.param));
                         });

TEST(HumanModel, BodyDetailsAreNamedAndTheFineOneHasTwiceTheVertices) {
  for (const BodyDetail detail : {BodyDetail::kStandard, BodyDetail::kFine})
    EXPECT_EQ(parseBodyDetail(bodyDetailName(detail)), detail);
  EXPECT_NE(
      testing::errorOf([] { parseBodyDetail("coarse"); }).find("body 'coarse': standard or fine"),
      std::string::npos);
  const int standard = loadGenericHuman(BodyDetail::kStandard).rest.vertexCount();
  const int fine = loadGenericHuman(BodyDetail::kFine).rest.vertexCount();
  EXPECT_GT(fine, 1.8 * standard);
  EXPECT_LT(fine, 2.2 * standard);
}

// A generic human whose file lists the hips' children in another order (another exporter): the
// tracker and the nodes index joints by the human order, and posed a contorted body from it
// (MPJPE 17 -> 298 mm, without a word). It is refused, naming the joint.
TEST(HumanModel, JointsOutOfTheHumanOrderAreRefusedByName) {
  const SkinnedMesh generic = makeHumanModel();
  EXPECT_NO_THROW(checkHumanJointOrder(generic.skeleton, "generic"));
  std::vector<Joint> joints = generic.skeleton.joints();
  std::swap(joints[kRightHip].name, joints[kLeftHip].name);
  const Skeleton swapped(joints);
  try {
    checkHumanJointOrder(swapped, "other.glb");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("other.glb: joint 16 is 'left_hip' where the human "
                                         "skeleton has 'right_hip'"),
              std::string::npos)
        << e.what();
  }
  SkinnedMesh wrong = generic;
  wrong.skeleton = swapped;
  EXPECT_THROW(PoseTracker(makeRingRig({}), wrong), std::invalid_argument);
}

// A broken export's NaN or absurd vertex is refused with the vertex, before it reaches the
// tracker's calibration (which threw about a joint's offset, in the studio's motion-capture
// thread).
TEST(HumanModel, AVertexThatIsNotANumberIsRefused) {
  SkinnedMesh mesh = makeHumanModel();
  mesh.rest.positions(1, 7) = std::numeric_limits<float>::quiet_NaN();
  try {
    mesh.validate();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 7 is at"), std::string::npos) << e.what();
  }
  mesh = makeHumanModel();
  mesh.rest.positions(2, 9) = 1e30f;
  EXPECT_THROW(mesh.validate(), std::invalid_argument);
  mesh = makeHumanModel();
  mesh.skin.weights[3][0] = std::numeric_limits<float>::infinity();
  try {
    mesh.validate();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 3 has a weight of inf"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lumistage
