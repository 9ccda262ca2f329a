// A rigged human from elsewhere made into one the pipeline poses with the human skeleton: its
// joints found by name or by the bone chains' geometry, its bind pose turned into our T-pose.
#include "core/body/body_mapping.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <filesystem>
#include <map>
#include <numbers>

#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/body/mesh_io.h"
#include "core/body/motion_library.h"
#include "core/net/posed_body.h"
#include "core/tracking/mesh_silhouette.h"
#include "tests/core/tracking/synthetic_stage.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const fs::path kCesiumMan = testing::realData() / "bodies" / "CesiumMan.glb";

// A body on the human skeleton's bones whose joints are called `names` (ours when empty), with
// its arms hanging `arms_down_rad` below the T-pose, a root joint on the floor above the pelvis
// and a finger below each hand; a small tetrahedron at every joint, skinned to it.
SkinnedMesh makeRig(const std::map<int, std::string>& names, double arms_down_rad) {
  const Skeleton human = makeHumanSkeleton();
  std::vector<Joint> joints;
  joints.push_back({"root", -1, Vector3d::Zero(), {}});
  for (const Joint& j : human.joints()) {
    Joint copy = j;
    copy.parent = j.parent + 1;
    if (j.parent < 0) copy.offset_m = j.offset_m;
    const auto it = names.find(static_cast<int>(joints.size()) - 1);
    if (it != names.end()) copy.name = it->second;
    joints.push_back(copy);
  }
  for (int side : {kRightShoulder, kLeftShoulder}) {
    const double down = side == kRightShoulder ? arms_down_rad : -arms_down_rad;
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(down, Vector3d::UnitY()).toRotationMatrix();
    for (int k = 1; k <= 3; ++k)
      joints[side + 1 + k].offset_m = turn * joints[side + 1 + k].offset_m;
  }
  for (int hand : {kRightHand, kLeftHand}) {
    const Vector3d along = joints[hand + 1].offset_m.normalized() * 0.08;
    joints.push_back(
        {names.empty() ? human.joint(hand).name + "_finger" : "x" + std::to_string(hand),
         hand + 1,
         along,
         {}});
  }
  SkinnedMesh mesh;
  mesh.skeleton = Skeleton(std::move(joints));
  const int n = mesh.skeleton.jointCount();
  mesh.rest.positions.resize(3, 4 * n);
  const Eigen::Vector3f tetra[4] = {{0.02f, 0.02f, 0.02f},
                                    {0.02f, -0.02f, -0.02f},
                                    {-0.02f, 0.02f, -0.02f},
                                    {-0.02f, -0.02f, 0.02f}};
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < 4; ++k) {
      mesh.rest.positions.col(4 * j + k) =
          mesh.skeleton.restPositions()[j].cast<float>() + tetra[k];
      mesh.skin.joints.push_back({static_cast<uint16_t>(j), 0, 0, 0});
      mesh.skin.weights.push_back({1, 0, 0, 0});
    }
    const int b = 4 * j;
    mesh.rest.triangles.emplace_back(b + 0, b + 1, b + 2);
    mesh.rest.triangles.emplace_back(b + 0, b + 3, b + 1);
    mesh.rest.triangles.emplace_back(b + 0, b + 2, b + 3);
    mesh.rest.triangles.emplace_back(b + 1, b + 3, b + 2);
  }
  mesh.rest.computeNormals();
  return mesh;
}

// Names that say nothing: j0, j1, ... in the file's order.
std::map<int, std::string> meaninglessNames() {
  std::map<int, std::string> names;
  for (int j = 0; j < kHumanJointCount; ++j) names[j] = "j" + std::to_string(j);
  return names;
}

TEST(BodyMapping, ARigWhoseNamesSayNothingIsMappedByItsBoneChains) {
  const SkinnedMesh rig = makeRig(meaninglessNames(), 0.0);
  const BodyMapping m = mapHumanJoints(rig.skeleton, "rig");
  for (int t = 0; t < kHumanJointCount; ++t) {
    EXPECT_EQ(m.file_joint[t], t + 1) << makeHumanSkeleton().joint(t).name;
    EXPECT_EQ(m.how[t], JointFound::kGeometry) << makeHumanSkeleton().joint(t).name;
  }
  // The fingers' weights go to the hands, the root's to the pelvis.
  EXPECT_EQ(m.weights_to[0], kPelvis);
  EXPECT_EQ(m.weights_to[kHumanJointCount + 1], kRightHand);
  EXPECT_EQ(m.weights_to[kHumanJointCount + 2], kLeftHand);
}

TEST(BodyMapping, MixamoAndRigifyNamesAreMappedByName) {
  const std::map<int, std::string> mixamo = {
      {kPelvis, "mixamorig:Hips"},           {kSpine1, "mixamorig:Spine"},
      {kRightHip, "mixamorig:RightUpLeg"},   {kRightKnee, "mixamorig:RightLeg"},
      {kRightAnkle, "mixamorig:RightFoot"},  {kLeftShoulder, "mixamorig:LeftArm"},
      {kLeftElbow, "mixamorig:LeftForeArm"}, {kLeftWrist, "mixamorig:LeftHand"}};
  const std::map<int, std::string> rigify = {
      {kPelvis, "spine"},         {kSpine1, "spine.001"},    {kSpine3, "spine.003"},
      {kLeftHip, "DEF-thigh.L"},  {kLeftKnee, "DEF-shin.L"}, {kRightShoulder, "upper_arm.R"},
      {kRightElbow, "forearm.R"}, {kRightWrist, "hand.R"},   {kRightClavicle, "shoulder.R"}};
  for (const auto& names : {mixamo, rigify}) {
    std::map<int, std::string> all = meaninglessNames();
    for (const auto& [t, name] : names) all[t] = name;
    const BodyMapping m = mapHumanJoints(makeRig(all, 0.0).skeleton, "rig");
    for (const auto& [t, name] : names) {
      EXPECT_EQ(m.file_joint[t], t + 1) << name;
      EXPECT_EQ(m.how[t], JointFound::kName) << name;
    }
  }
}

TEST(BodyMapping, ABodyBoundWithItsArmsDownStandsInOurTPoseAtRest) {
  const SkinnedMesh rig = makeRig({}, 1.2);  // arms 69 degrees below level
  const BodyMapping m = mapHumanJoints(rig.skeleton, "rig");
  const SkinnedMesh body = fitToHumanSkeleton(rig, m, "rig");
  EXPECT_NO_THROW(checkHumanJointOrder(body.skeleton, "rig"));
  const auto& rest = body.skeleton.restPositions();
  const Skeleton human = makeHumanSkeleton();
  const auto& ours = human.restPositions();
  for (int t = 0; t < kHumanJointCount; ++t) {
    EXPECT_LT((rest[t] - rest[kPelvis] - (ours[t] - ours[kPelvis])).norm(), 1e-5)
        << makeHumanSkeleton().joint(t).name;
  }
  for (int side : {kRightShoulder, kLeftShoulder}) {
    EXPECT_NEAR(rest[side + 2].z(), rest[side].z(), 1e-5);          // the wrist level
    EXPECT_GT(std::abs(rest[side + 2].x() - rest[side].x()), 0.5);  // and out to the side
  }
  // The wrists' tetrahedra came along: still around the wrist joints. Standing on the floor.
  for (int side : {kRightWrist, kLeftWrist}) {
    const Eigen::Vector3f centre =
        body.rest.positions.middleCols(4 * (side + 1), 4).rowwise().mean();
    EXPECT_LT((centre.cast<double>() - rest[side]).norm(), 1e-4);
  }
  EXPECT_NEAR(body.rest.positions.row(2).minCoeff(), 0.0f, 1e-6f);
}

TEST(BodyMapping, ABodyWithoutLegsIsRefusedNamingItsFile) {
  SkinnedMesh rig = makeRig(meaninglessNames(), 0.0);
  std::vector<Joint> upper;
  for (const Joint& j : rig.skeleton.joints()) {
    if (upper.size() >= kRightHip + 1) break;  // root and the joints up to the hands
    upper.push_back(j);
  }
  try {
    mapHumanJoints(Skeleton(upper), "legless.glb");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("legless.glb"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("leg"), std::string::npos) << e.what();
  }
}

// Khronos' CesiumMan (../shared/realdata, where present): 19 joints named by limb, side and a
// number that runs up the right arm and down the left one.
TEST(BodyMapping, CesiumMansJointsAreTheRightOnes) {
  if (!fs::exists(kCesiumMan)) GTEST_SKIP() << "no " << kCesiumMan.string();
  const SkinnedMesh file = loadSkinnedMesh(kCesiumMan);
  const BodyMapping m = mapHumanJoints(file.skeleton, kCesiumMan.string());
  const std::map<int, std::string> expected = {{kPelvis, "Skeleton_torso_joint_1"},
                                               {kSpine3, "torso_joint_3"},
                                               {kNeck, "Skeleton_neck_joint_1"},
                                               {kHead, "Skeleton_neck_joint_2"},
                                               {kRightHip, "leg_joint_R_1"},
                                               {kRightKnee, "leg_joint_R_2"},
                                               {kRightAnkle, "leg_joint_R_3"},
                                               {kLeftHip, "leg_joint_L_1"},
                                               {kLeftKnee, "leg_joint_L_2"},
                                               {kLeftAnkle, "leg_joint_L_3"},
                                               {kRightShoulder, "Skeleton_arm_joint_R"},
                                               {kRightElbow, "Skeleton_arm_joint_R__2_"},
                                               {kRightWrist, "Skeleton_arm_joint_R__3_"},
                                               {kLeftShoulder, "Skeleton_arm_joint_L__4_"},
                                               {kLeftElbow, "Skeleton_arm_joint_L__3_"},
                                               {kLeftWrist, "Skeleton_arm_joint_L__2_"}};
  for (const auto& [t, name] : expected) {
    ASSERT_GE(m.file_joint[t], 0) << makeHumanSkeleton().joint(t).name;
    EXPECT_EQ(file.skeleton.joint(m.file_joint[t]).name, name) << makeHumanSkeleton().joint(t).name;
  }
  // Its names' sides are the actor's: the right leg at +x.
  const auto& at = file.skeleton.restPositions();
  EXPECT_GT(at[m.file_joint[kRightHip]].x(), at[m.file_joint[kLeftHip]].x());
  // The bone chains alone find the same joints.
  std::vector<Joint> renamed = file.skeleton.joints();
  for (size_t j = 0; j < renamed.size(); ++j) renamed[j].name = "j" + std::to_string(j);
  const BodyMapping g = mapHumanJoints(Skeleton(renamed), "renamed");
  for (const auto& [t, name] : expected)
    EXPECT_EQ(g.file_joint[t], m.file_joint[t]) << makeHumanSkeleton().joint(t).name;

  const SkinnedMesh body = fitToHumanSkeleton(file, m, kCesiumMan.string());
  const auto& rest = body.skeleton.restPositions();
  for (int side : {kRightShoulder, kLeftShoulder})
    EXPECT_NEAR(rest[side + 2].z(), rest[side].z(), 0.01);  // T-pose: wrists level
  EXPECT_GT(rest[kRightWrist].x() - rest[kLeftWrist].x(), 1.0);
  const float height = body.rest.positions.row(2).maxCoeff();
  EXPECT_GT(height, 1.4f);
  EXPECT_LT(height, 1.6f);
}

// `body` posed by `message` as the nodes pose it.
Eigen::Matrix3Xf posed(const SkinnedMesh& body, const PoseData& message) {
  Pose pose;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  posedBodyMesh(body, message, pose, transforms, positions, normals);
  return positions;
}

// The mean IoU over the cameras of the silhouettes of a posed body and `actual`.
double silhouetteIou(const SkinnedMesh& body, const Eigen::Matrix3Xf& positions, const Rig& rig,
                     const std::vector<const LowResSilhouette*>& actual, int step) {
  double sum = 0;
  LowResSilhouette mine;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    rasterizeSilhouette(positions, body.rest.triangles, rig.camera(c), c, step, mine);
    int both = 0, either = 0;
    for (size_t b = 0; b < mine.bits.size(); ++b) {
      both += std::popcount(unsigned(mine.bits[b] & actual[c]->bits[b]));
      either += std::popcount(unsigned(mine.bits[b] | actual[c]->bits[b]));
    }
    sum += either > 0 ? double(both) / either : 0.0;
  }
  return sum / rig.cameraCount();
}

// Where the vertices that joint `j` moves most lie, on average.
Vector3d centroidOf(const SkinnedMesh& body, const Eigen::Matrix3Xf& positions, int j) {
  Vector3d sum = Vector3d::Zero();
  int n = 0;
  for (int v = 0; v < body.rest.vertexCount(); ++v) {
    const auto& w = body.skin.weights[v];
    const int k = int(std::max_element(w.begin(), w.end()) - w.begin());
    if (body.skin.joints[v][k] != j) continue;
    sum += positions.col(v).cast<double>();
    ++n;
  }
  return n > 0 ? Vector3d(sum / n) : Vector3d::Constant(1e9);
}

// CesiumMan as the body the nodes pose while the tracker follows the virtual studio's actor (1.82
// m, clothes) walking: every frame tracked (MPJPE measured 13.9 mm over 30 frames), CesiumMan
// fitted to the tracked joints covers the actor's silhouettes (mean IoU measured 0.62; the generic
// human 0.77: CesiumMan is slighter than the clothed actor), and what his wrists move (his hands,
// beyond the wrists) lies 9.5 cm from the actor's wrists on average (arms left hanging as bound,
// half a metre). Bounds with margin.
TEST(BodyMapping, CesiumManIsPosedOverAWalkingActor) {
  if (!fs::exists(kCesiumMan)) GTEST_SKIP() << "no " << kCesiumMan.string();
  const SkinnedMesh cesium = loadHumanBody(kCesiumMan);
  testing::SyntheticStage stage(std::string(LUMISTAGE_TEST_RESOURCE_DIR) +
                                "/studio/reference.yaml");
  PoseTracker tracker(stage.config.rig, trackingModelFor(cesium));
  const MotionClip clip = makeBuiltinClip("walk", stage.actor.skeleton, 30.0, 2.5);
  const int frames = 30;
  int tracked = 0;
  double mean_m = 0, iou = 0, hands_m = 0;
  for (int f = 0; f < frames; ++f) {
    const auto& silhouettes = stage.render(clip.sample(f / 30.0));
    const TrackResult& r = tracker.track(silhouettes);
    if (!r.valid()) continue;
    ++tracked;
    if (f == 0) continue;
    mean_m += testing::mpjpe(r.joints, stage.joints) / (frames - 1);
    const PoseData message = poseMessageFor(cesium.skeleton, tracker.skeleton(), r.pose, r.joints);
    const Eigen::Matrix3Xf positions = posed(cesium, message);
    iou +=
        silhouetteIou(cesium, positions, stage.config.rig, silhouettes, stage.step) / (frames - 1);
    for (int wrist : {kRightWrist, kLeftWrist})
      hands_m +=
          (centroidOf(cesium, positions, wrist) - stage.joints[wrist]).norm() / (2 * (frames - 1));
  }
  EXPECT_EQ(tracked, frames);
  EXPECT_LT(mean_m, 0.025);
  EXPECT_GT(iou, 0.55);
  EXPECT_LT(hands_m, 0.14);
}

}  // namespace
}  // namespace lumistage
