#include "core/body/mesh_io.h"

#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>

#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "tests/core/body/body_test_meshes.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

fs::path testFolder() {
  return testing::testFolder("mesh_io");
}

// A closed square tube around a 3-joint chain (z up, 2 m), rings of 4 vertices every 0.5 m; the
// ring at the middle joint blends the two, the top ring blends the tip in.
SkinnedMesh makeChainMesh() {
  SkinnedMesh mesh;
  const JointLimits free{Eigen::Vector3d::Constant(-kPi), Eigen::Vector3d::Constant(kPi)};
  mesh.skeleton = Skeleton({{"root", -1, {0.1, -0.2, 0.3}, free},
                            {"mid", 0, {0, 0, 1}, free},
                            {"tip", 1, {0, 0.2, 1}, free}});
  constexpr int kRings = 5;
  mesh.rest.positions.resize(3, 4 * kRings);
  const float corners[4][2] = {{-0.1f, -0.1f}, {0.1f, -0.1f}, {0.1f, 0.1f}, {-0.1f, 0.1f}};
  for (int r = 0; r < kRings; ++r) {
    for (int k = 0; k < 4; ++k) {
      mesh.rest.positions.col(4 * r + k) =
          Eigen::Vector3f(0.1f + corners[k][0], -0.2f + corners[k][1], 0.3f + 0.5f * r);
      std::array<uint16_t, 4> joints{0, 0, 0, 0};
      std::array<float, 4> weights{1, 0, 0, 0};
      if (r == 2) joints = {0, 1, 0, 0}, weights = {0.5f, 0.5f, 0, 0};
      if (r == 3) joints = {1, 0, 0, 0};
      if (r == 4) joints = {1, 2, 0, 0}, weights = {0.7f, 0.3f, 0, 0};
      mesh.skin.joints.push_back(joints);
      mesh.skin.weights.push_back(weights);
      mesh.materials.push_back(static_cast<uint8_t>(r % 3));
    }
  }
  for (int r = 0; r + 1 < kRings; ++r) {
    for (int k = 0; k < 4; ++k) {
      const int a = 4 * r + k, b = 4 * r + (k + 1) % 4, c = a + 4, d = b + 4;
      mesh.rest.triangles.emplace_back(a, b, d);
      mesh.rest.triangles.emplace_back(a, d, c);
    }
  }
  mesh.rest.triangles.emplace_back(0, 2, 1);
  mesh.rest.triangles.emplace_back(0, 3, 2);
  const int top = 4 * (kRings - 1);
  mesh.rest.triangles.emplace_back(top, top + 1, top + 2);
  mesh.rest.triangles.emplace_back(top, top + 2, top + 3);
  mesh.rest.computeNormals();
  return mesh;
}

// A triangle rigged to `bones` joints hanging off one root node, written as Assimp's own binary
// format (which keeps any number of weights): vertex 0 is weighted by every bone, vertex 1 by the
// first, vertex 2 by none unless `weight_all`.
void writeRiggedTriangle(const fs::path& path, int bones, bool weight_all) {
  aiScene scene;
  scene.mRootNode = new aiNode("root");
  auto* armature = new aiNode("armature");
  armature->mParent = scene.mRootNode;
  scene.mRootNode->mNumChildren = 1;
  scene.mRootNode->mChildren = new aiNode* [1] { armature };
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  armature->mNumChildren = bones;
  armature->mChildren = new aiNode*[bones];
  for (int b = 0; b < bones; ++b) {
    armature->mChildren[b] = new aiNode("bone" + std::to_string(b));
    armature->mChildren[b]->mParent = armature;
  }
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial };
  auto* mesh = new aiMesh;
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh* [1] { mesh };
  mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  mesh->mNumVertices = 3;
  mesh->mVertices = new aiVector3D[3]{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh->mNormals = new aiVector3D[3]{{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh->mNumFaces = 1;
  mesh->mFaces = new aiFace[1];
  mesh->mFaces[0].mNumIndices = 3;
  mesh->mFaces[0].mIndices = new unsigned[3]{0, 1, 2};
  mesh->mNumBones = bones;
  mesh->mBones = new aiBone*[bones];
  for (int b = 0; b < bones; ++b) {
    auto* bone = new aiBone;
    bone->mName = "bone" + std::to_string(b);
    std::vector<aiVertexWeight> weights{{0, 1.0f / bones}};
    if (b == 0) weights.emplace_back(1, 1.0f);
    if (b == 0 && weight_all) weights.emplace_back(2, 1.0f);
    bone->mNumWeights = static_cast<unsigned>(weights.size());
    bone->mWeights = new aiVertexWeight[weights.size()];
    std::copy(weights.begin(), weights.end(), bone->mWeights);
    mesh->mBones[b] = bone;
  }
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(&scene, "assbin", path.string()), AI_SUCCESS)
      << exporter.GetErrorString();
}

// A random pose within limits (root: any turn, a small translation).
Pose randomPose(const Skeleton& s, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  Pose pose = Pose::rest(s.jointCount());
  pose.root_translation_m = Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) * 0.2);
  pose.angles_rad[0] = Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, 4 * unit(rng) - 2);
  for (int j = 1; j < s.jointCount(); ++j) {
    const JointLimits& l = s.joint(j).limits;
    for (int a = 0; a < 3; ++a) {
      pose.angles_rad[j][a] = l.lower_rad[a] + unit(rng) * (l.upper_rad[a] - l.lower_rad[a]);
    }
  }
  return pose;
}

// The same pose on another skeleton with the same joint names.
Pose byName(const Pose& pose, const Skeleton& from, const Skeleton& to) {
  Pose out = Pose::rest(to.jointCount());
  out.root_translation_m = pose.root_translation_m;
  for (int j = 0; j < from.jointCount(); ++j) {
    const std::optional<int> k = to.findJoint(from.joint(j).name);
    if (k) out.angles_rad[*k] = pose.angles_rad[j];
  }
  return out;
}

void expectSameMesh(const SkinnedMesh& original, const SkinnedMesh& loaded) {
  // Skeleton: names, parents (by name), rest positions, limits.
  ASSERT_EQ(loaded.skeleton.jointCount(), original.skeleton.jointCount());
  for (int j = 0; j < original.skeleton.jointCount(); ++j) {
    const Joint& a = original.skeleton.joint(j);
    const std::optional<int> k = loaded.skeleton.findJoint(a.name);
    ASSERT_TRUE(k) << a.name;
    const Joint& b = loaded.skeleton.joint(*k);
    EXPECT_EQ(a.parent < 0 ? "" : original.skeleton.joint(a.parent).name,
              b.parent < 0 ? "" : loaded.skeleton.joint(b.parent).name);
    EXPECT_LT((original.skeleton.restPositions()[j] - loaded.skeleton.restPositions()[*k]).norm(),
              1e-5)
        << a.name;
    EXPECT_EQ(a.limits, b.limits) << a.name;
  }
  // Vertices: same count, each original one matched by position (order may change).
  ASSERT_EQ(loaded.rest.vertexCount(), original.rest.vertexCount());
  ASSERT_EQ(loaded.rest.triangles.size(), original.rest.triangles.size());
  ASSERT_EQ(loaded.materials.size(), original.materials.size());
  std::vector<int> match(original.rest.vertexCount());
  for (int v = 0; v < original.rest.vertexCount(); ++v) {
    Eigen::Index nearest = 0;
    const double distance = (loaded.rest.positions.colwise() - original.rest.positions.col(v))
                                .colwise()
                                .norm()
                                .minCoeff(&nearest);
    ASSERT_LT(distance, 1e-5) << "vertex " << v;
    match[v] = static_cast<int>(nearest);
    EXPECT_LT((loaded.rest.normals.col(nearest) - original.rest.normals.col(v)).norm(), 1e-4);
    if (!original.materials.empty()) {
      EXPECT_EQ(loaded.materials[nearest], original.materials[v]);
    }
  }
  // Posed: the same random poses give the same skinned vertices.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const Pose pose = randomPose(original.skeleton, rng);
    const Pose mapped = byName(pose, original.skeleton, loaded.skeleton);
    std::vector<Eigen::Affine3f> ta, tb;
    original.skeleton.skinningTransforms(pose, ta);
    loaded.skeleton.skinningTransforms(mapped, tb);
    Eigen::Matrix3Xf pa, na, pb, nb;
    skinMesh(original, ta, pa, na);
    skinMesh(loaded, tb, pb, nb);
    for (int v = 0; v < original.rest.vertexCount(); ++v) {
      EXPECT_LT((pa.col(v) - pb.col(match[v])).norm(), 1e-4) << "vertex " << v;
    }
  }
}

TEST(MeshIo, ChainMeshRoundTripsThroughGlbAndGltf) {
  const fs::path folder = testFolder();
  const SkinnedMesh mesh = makeChainMesh();
  ASSERT_EQ(checkClosedManifold(mesh.rest).error(), "");
  for (const char* name : {"chain.glb", "chain.gltf"}) {
    SCOPED_TRACE(name);
    saveSkinnedMeshGltf(mesh, folder / name);
    saveSkinnedMeshGltf(mesh, folder / name);  // replaces the first
    expectSameMesh(mesh, loadSkinnedMesh(folder / name));
  }
  // Exactly the .glb, the .gltf and its buffer: no temporaries left behind.
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    files.push_back(entry.path().filename().string());
  }
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"chain.bin", "chain.glb", "chain.gltf"}));
  fs::remove_all(folder);
}

TEST(MeshIo, HumanMeshRoundTripsWithLimitsByName) {
  const fs::path folder = testFolder();
  const SkinnedMesh mesh = testing::makeHumanMesh();
  for (const char* name : {"human.glb", "human.gltf"}) {
    SCOPED_TRACE(name);
    saveSkinnedMeshGltf(mesh, folder / name);
    const SkinnedMesh loaded = loadSkinnedMesh(folder / name);
    expectSameMesh(mesh, loaded);
    EXPECT_TRUE(loaded.materials.empty());
  }
  fs::remove_all(folder);
}

TEST(MeshIo, BadFilesGiveClearErrors) {
  const fs::path folder = testFolder();
  std::string m = testing::errorOf([&] { loadSkinnedMesh(folder / "missing.glb"); });
  EXPECT_NE(m.find("missing.glb"), std::string::npos) << m;
  EXPECT_NE(m.find("no such file"), std::string::npos) << m;

  {
    std::ofstream out(folder / "garbage.glb", std::ios::binary);
    std::mt19937 rng(3);
    for (int i = 0; i < 4096; ++i) out.put(static_cast<char>(rng() & 0xff));
  }
  m = testing::errorOf([&] { loadSkinnedMesh(folder / "garbage.glb"); });
  EXPECT_NE(m.find("garbage.glb"), std::string::npos) << m;
  EXPECT_NE(m.find("cannot read"), std::string::npos) << m;

  {
    std::ofstream out(folder / "static.obj");
    out << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  m = testing::errorOf([&] { loadSkinnedMesh(folder / "static.obj"); });
  EXPECT_NE(m.find("static.obj"), std::string::npos) << m;
  EXPECT_NE(m.find("no skeleton"), std::string::npos) << m;

  {
    std::ofstream out(folder / "points.obj");
    out << "v 0 0 0\nv 1 0 0\np 1 2\n";
  }
  m = testing::errorOf([&] { loadSkinnedMesh(folder / "points.obj"); });
  EXPECT_NE(m.find("points.obj"), std::string::npos) << m;
  EXPECT_NE(m.find("no mesh"), std::string::npos) << m;

  m = testing::errorOf([&] { saveSkinnedMeshGltf(makeChainMesh(), folder / "chain.fbx"); });
  EXPECT_NE(m.find("chain.fbx"), std::string::npos) << m;
  EXPECT_NE(m.find("expected .glb or .gltf"), std::string::npos) << m;
  fs::remove_all(folder);
}

TEST(MeshIo, BadWeightsGiveClearErrors) {
  const fs::path folder = testFolder();
  // Six equal influences on a vertex: four kept (mesh_import_test.cpp has more), and the two bones
  // that so lose their only weight stay joints of the skeleton.
  writeRiggedTriangle(folder / "crowded.assbin", 6, true);
  const SkinnedMesh crowded = loadSkinnedMesh(folder / "crowded.assbin");
  EXPECT_EQ(crowded.skeleton.jointCount(), 7);
  for (const auto& weights : crowded.skin.weights) {
    EXPECT_NEAR(weights[0] + weights[1] + weights[2] + weights[3], 1, 1e-5);
  }
  writeRiggedTriangle(folder / "unweighted.assbin", 2, false);
  std::string m = testing::errorOf([&] { loadSkinnedMesh(folder / "unweighted.assbin"); });
  EXPECT_NE(m.find("1 of 3 vertices have no bone weights"), std::string::npos) << m;
  // Well-formed: the skeleton is the bones and their common ancestor, weights normalised.
  writeRiggedTriangle(folder / "good.assbin", 3, true);
  const SkinnedMesh mesh = loadSkinnedMesh(folder / "good.assbin");
  ASSERT_EQ(mesh.skeleton.jointCount(), 4);
  EXPECT_EQ(mesh.skeleton.joint(0).name, "armature");
  EXPECT_EQ(mesh.skeleton.joint(3).name, "bone2");
  EXPECT_EQ(mesh.skeleton.joint(3).limits.upper_rad, Eigen::Vector3d::Constant(kPi));
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
