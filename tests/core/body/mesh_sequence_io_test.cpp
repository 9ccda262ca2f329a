#include "core/body/mesh_sequence_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cstring>
#include <filesystem>
#include <string>

#include "core/base/error.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

// A tetrahedron, moved up by `lift` metres.
TriangleMesh tetrahedron(float lift) {
  TriangleMesh mesh;
  mesh.positions.resize(3, 4);
  mesh.positions << 0, 1, 0, 0,  //
      0, 0, 1, 0,                //
      0, 0, 0, 1;
  mesh.positions.row(2).array() += lift;
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  mesh.computeNormals();
  return mesh;
}

const aiScene* import(Assimp::Importer& importer, const fs::path& path) {
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  EXPECT_NE(scene, nullptr) << path << ": " << importer.GetErrorString();
  return scene;
}

TEST(MeshSequenceIo, AnimatedGlbShowsEachFrameDuringItsTimeOnly) {
  const fs::path path = testing::testFolder("mesh_sequence_io") / "sequence.glb";
  const std::vector<TriangleMesh> frames = {tetrahedron(0), tetrahedron(0.5f), tetrahedron(1)};
  saveMeshSequenceGlb(path, frames, 25);

  Assimp::Importer importer;
  const aiScene* scene = import(importer, path);
  ASSERT_NE(scene, nullptr);
  ASSERT_EQ(scene->mNumMeshes, 3u);
  for (unsigned f = 0; f < 3; ++f) {
    const aiMesh* mesh = scene->mMeshes[f];
    ASSERT_EQ(mesh->mNumVertices, 4u);
    ASSERT_EQ(mesh->mNumFaces, 4u);
    ASSERT_TRUE(mesh->HasNormals());
    for (unsigned v = 0; v < 4; ++v) {
      // glTF axes: X = -x, Y = z, Z = y.
      const Eigen::Vector3f p = frames[f].positions.col(v);
      EXPECT_FLOAT_EQ(mesh->mVertices[v].x, -p.x());
      EXPECT_FLOAT_EQ(mesh->mVertices[v].y, p.z());
      EXPECT_FLOAT_EQ(mesh->mVertices[v].z, p.y());
    }
    for (unsigned t = 0; t < 4; ++t)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(int(mesh->mFaces[t].mIndices[k]), frames[f].triangles[t][k]);
  }
  ASSERT_EQ(scene->mNumAnimations, 1u);
  const aiAnimation* animation = scene->mAnimations[0];
  ASSERT_EQ(animation->mNumChannels, 3u);
  const double ticks = animation->mTicksPerSecond > 0 ? animation->mTicksPerSecond : 1.0;
  for (unsigned c = 0; c < 3; ++c) {
    const aiNodeAnim* channel = animation->mChannels[c];
    const std::string name = channel->mNodeName.C_Str();
    ASSERT_EQ(name.rfind("frame_00000", 0), 0u) << name;
    const int f = name.back() - '0';
    // The scale is 1 from f / fps and 0 at every other key.
    bool shown = false;
    for (unsigned k = 0; k < channel->mNumScalingKeys; ++k) {
      const double t = channel->mScalingKeys[k].mTime / ticks;
      const float s = channel->mScalingKeys[k].mValue.x;
      if (std::abs(t - f / 25.0) < 1e-6) {
        EXPECT_FLOAT_EQ(s, 1.0f) << name;
        shown = true;
      } else {
        EXPECT_FLOAT_EQ(s, 0.0f) << name << " at " << t;
      }
    }
    EXPECT_TRUE(shown) << name;
  }
}

TEST(MeshSequenceIo, PlyAndObjReadBackThroughAssimp) {
  const fs::path folder = testing::testFolder("mesh_sequence_io");
  const TriangleMesh mesh = tetrahedron(0.25f);
  saveMeshPly(folder / "frame.ply", mesh);
  saveMeshObj(folder / "frame.obj", mesh);
  for (const char* file : {"frame.ply", "frame.obj"}) {
    Assimp::Importer importer;
    const aiScene* scene = import(importer, folder / file);
    ASSERT_NE(scene, nullptr);
    ASSERT_EQ(scene->mNumMeshes, 1u) << file;
    const aiMesh* read = scene->mMeshes[0];
    ASSERT_EQ(read->mNumFaces, 4u) << file;
    // OBJ and PLY keep our axes; readers may split vertices per face, so compare by face.
    for (unsigned t = 0; t < 4; ++t) {
      for (int k = 0; k < 3; ++k) {
        const aiVector3D& p = read->mVertices[read->mFaces[t].mIndices[k]];
        const Eigen::Vector3f expected = mesh.positions.col(mesh.triangles[t][k]);
        EXPECT_FLOAT_EQ(p.x, expected.x()) << file;
        EXPECT_FLOAT_EQ(p.y, expected.y()) << file;
        EXPECT_FLOAT_EQ(p.z, expected.z()) << file;
      }
    }
  }
}

TEST(MeshSequenceIo, BadSequencesAreRefusedNamingTheFile) {
  const fs::path path = testing::testFolder("mesh_sequence_io") / "bad.glb";
  EXPECT_EQ(testing::errorOf([&] { saveMeshSequenceGlb(path, {}, 25); }),
            path.string() + ": no frames to write");
  TriangleMesh broken = tetrahedron(0);
  broken.triangles.push_back({0, 1, 7});
  EXPECT_EQ(
      testing::errorOf([&] {
        saveMeshSequenceGlb(path, {tetrahedron(0), broken}, 25);
      }),
      path.string() + ": frame 1 has a triangle with a vertex out of range (it has 4 vertices)");
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace lumistage
