// Rigged meshes from other tools: more than four influences per vertex, and every format's axes and
// units (mesh_io.h, mesh_axes.h).

#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/body/mesh_axes.h"
#include "core/body/mesh_io.h"
#include "tests/core/body/body_test_meshes.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using V3 = Eigen::Vector3f;

fs::path testFolder() {
  return testing::testFolder("mesh_import");
}

// What spdlog says while one lives.
class LogCapture {
 public:
  LogCapture() : previous_(spdlog::default_logger()) {
    spdlog::set_default_logger(std::make_shared<spdlog::logger>(
        "mesh_import_test", std::make_shared<spdlog::sinks::ostream_sink_st>(text_)));
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }
  std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
};

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// ---------------------------------------------------------------------------------------------
// More than four influences.

std::string base64(const std::vector<uint8_t>& bytes) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t v = uint32_t{bytes[i]} << 16;
    if (n > 1) v |= uint32_t{bytes[i + 1]} << 8;
    if (n > 2) v |= bytes[i + 2];
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += n > 1 ? kDigits[(v >> 6) & 63] : '=';
    out += n > 2 ? kDigits[v & 63] : '=';
  }
  return out;
}

template <typename T>
void append(std::vector<uint8_t>& bytes, T value) {
  uint8_t raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes.insert(bytes.end(), raw, raw + sizeof(T));
}

using Influences = std::vector<std::pair<int, float>>;  // (bone, weight)

constexpr float kTetrahedron[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

// A glTF 2.0 file written by hand (JSON, its buffer inline in base64): a tetrahedron (glTF
// coordinates kTetrahedron) skinned to eight bones "bone0".."bone7" under an "armature" node,
// through two sets of four influences, JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1, which each
// vertex's list fills in order.
void writeGltfWithEightInfluences(const fs::path& path, const std::vector<Influences>& vertices) {
  std::vector<uint8_t> buffer;
  std::vector<std::pair<size_t, size_t>> views;  // (offset, length)
  const auto view = [&](auto&& fill) {
    const size_t start = buffer.size();
    fill();
    views.emplace_back(start, buffer.size() - start);
  };
  view([&] {
    for (const auto& p : kTetrahedron) {
      for (float c : p) append(buffer, c);
    }
  });
  for (size_t set = 0; set < 2; ++set) {
    view([&] {
      for (const Influences& v : vertices) {
        for (size_t k = 4 * set; k < 4 * set + 4; ++k)
          append<uint16_t>(buffer, k < v.size() ? v[k].first : 0);
      }
    });
    view([&] {
      for (const Influences& v : vertices) {
        for (size_t k = 4 * set; k < 4 * set + 4; ++k)
          append<float>(buffer, k < v.size() ? v[k].second : 0);
      }
    });
  }
  view([&] {  // inverse bind matrices (column major): bone b sits at x = 0.1 b
    for (int b = 0; b < 8; ++b) {
      for (int k = 0; k < 16; ++k) append<float>(buffer, k % 5 == 0 ? 1 : k == 12 ? -0.1f * b : 0);
    }
  });
  view([&] {
    for (uint16_t i : {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}) append(buffer, i);
  });

  std::ostringstream json;
  json << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,9]}],)"
       << R"("nodes":[{"name":"armature","children":[1,2,3,4,5,6,7,8]})";
  for (int b = 0; b < 8; ++b)
    json << R"(,{"name":"bone)" << b << R"(","translation":[)" << 0.1 * b << ",0,0]}";
  json << R"(,{"name":"body","mesh":0,"skin":0}],)"
       << R"("skins":[{"joints":[1,2,3,4,5,6,7,8],"inverseBindMatrices":5}],)"
       << R"("meshes":[{"primitives":[{"attributes":{"POSITION":0,"JOINTS_0":1,"WEIGHTS_0":2,)"
       << R"("JOINTS_1":3,"WEIGHTS_1":4},"indices":6}]}],)"
       << R"("accessors":[)"
       << R"({"bufferView":0,"componentType":5126,"count":4,"type":"VEC3",)"
       << R"("min":[0,0,0],"max":[1,1,1]},)"
       << R"({"bufferView":1,"componentType":5123,"count":4,"type":"VEC4"},)"
       << R"({"bufferView":2,"componentType":5126,"count":4,"type":"VEC4"},)"
       << R"({"bufferView":3,"componentType":5123,"count":4,"type":"VEC4"},)"
       << R"({"bufferView":4,"componentType":5126,"count":4,"type":"VEC4"},)"
       << R"({"bufferView":5,"componentType":5126,"count":8,"type":"MAT4"},)"
       << R"({"bufferView":6,"componentType":5123,"count":12,"type":"SCALAR"}],)"
       << R"("bufferViews":[)";
  for (size_t v = 0; v < views.size(); ++v) {
    json << (v ? "," : "") << R"({"buffer":0,"byteOffset":)" << views[v].first
         << R"(,"byteLength":)" << views[v].second << "}";
  }
  json << R"(],"buffers":[{"byteLength":)" << buffer.size()
       << R"(,"uri":"data:application/octet-stream;base64,)" << base64(buffer) << R"("}]})";
  writeText(path, json.str());
}

TEST(MeshImport, MoreThanFourInfluencesKeepTheFourLargest) {
  const fs::path folder = testFolder();
  // Two vertices with eight influences, the largest four spread over both sets; ties nowhere
  // near the fourth place.
  const std::vector<Influences> vertices = {
      {{0, .04f}, {1, .2f}, {2, .06f}, {3, .25f}, {4, .1f}, {5, .15f}, {6, .08f}, {7, .12f}},
      {{7, .3f}, {6, .02f}, {5, .03f}, {4, .05f}, {3, .09f}, {2, .2f}, {1, .11f}, {0, .2f}},
      {{0, 1.f}},
      {{1, .5f}, {2, .5f}}};
  const fs::path file = folder / "eight.gltf";
  writeGltfWithEightInfluences(file, vertices);
  LogCapture log;
  const SkinnedMesh mesh = loadSkinnedMesh(file);

  // Every bone stays a joint, those that lost their weights too (bone4, bone6).
  ASSERT_EQ(mesh.skeleton.jointCount(), 9);
  ASSERT_EQ(mesh.rest.vertexCount(), 4);
  for (size_t v = 0; v < vertices.size(); ++v) {
    SCOPED_TRACE("vertex " + std::to_string(v));
    // glTF's (X, Y, Z) is our (-X, Z, Y).
    const V3 ours(-kTetrahedron[v][0], kTetrahedron[v][2], kTetrahedron[v][1]);
    Eigen::Index loaded = 0;
    ASSERT_LT((mesh.rest.positions.colwise() - ours).colwise().norm().minCoeff(&loaded), 1e-6);
    std::map<std::string, float> got;
    float sum = 0;
    for (int k = 0; k < kMaxInfluences; ++k) {
      const float w = mesh.skin.weights[loaded][k];
      sum += w;
      if (w > 0) got[mesh.skeleton.joint(mesh.skin.joints[loaded][k]).name] += w;
    }
    EXPECT_NEAR(sum, 1, 1e-5);
    Influences largest = vertices[v];
    std::sort(largest.begin(), largest.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    largest.resize(std::min<size_t>(largest.size(), kMaxInfluences));
    float kept = 0;
    for (const auto& [bone, weight] : largest) kept += weight;
    ASSERT_EQ(got.size(), largest.size());
    for (const auto& [bone, weight] : largest) {
      const std::string name = "bone" + std::to_string(bone);
      ASSERT_TRUE(got.count(name)) << name;
      EXPECT_NEAR(got[name], weight / kept, 1e-5) << name;
    }
  }
  // One warning, naming the file and how many vertices had more than four.
  const std::string said = log.text();
  EXPECT_NE(said.find(file.string() + ": 2 of 4 vertices have more than 4 bone influences (up to "
                                      "8): keeping the 4 largest"),
            std::string::npos)
      << said;
  EXPECT_EQ(std::count(said.begin(), said.end(), '\n'), 1) << said;
}

// ---------------------------------------------------------------------------------------------
// Axes and units.

// A file's frame: the axes (in its coordinates) along which the actor's left, front and up lie,
// and how many of its units make a metre.
struct Frame {
  V3 left, front, up;
  float units_per_metre = 1;
};

// Ours (left -x, front +y, up +z, metres) to the file's coordinates.
Eigen::Matrix3f oursToFile(const Frame& f) {
  Eigen::Matrix3f m;
  m.col(0) = -f.left;
  m.col(1) = f.front;
  m.col(2) = f.up;
  return f.units_per_metre * m;
}

const V3 kX = V3::UnitX(), kY = V3::UnitY(), kZ = V3::UnitZ();
const Frame kGltf{kX, kZ, kY, 1};  // glTF's, Maya's, Assimp's: +Y up, facing +Z

aiMatrix4x4 translation(const V3& t) {
  aiMatrix4x4 m;
  m.a4 = t.x();
  m.b4 = t.y();
  m.c4 = t.z();
  return m;
}

aiVector3D toAi(const V3& v) {
  return {v.x(), v.y(), v.z()};
}

// `mesh` as a scene whose coordinates are `to_file` times ours: a node per joint (translations),
// a bone per joint, normals, the winding turned where `to_file` mirrors.
std::unique_ptr<aiScene> sceneOf(const SkinnedMesh& mesh, const Eigen::Matrix3f& to_file) {
  const Skeleton& skeleton = mesh.skeleton;
  const int joints = skeleton.jointCount();
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode("scene_root");
  std::vector<aiNode*> nodes(joints);
  std::vector<std::vector<aiNode*>> children(joints + 1);  // the last: the root's
  for (int j = 0; j < joints; ++j) {
    nodes[j] = new aiNode(skeleton.joint(j).name);
    nodes[j]->mTransformation = translation(to_file * skeleton.joint(j).offset_m.cast<float>());
  }
  auto* body = new aiNode("body");
  body->mNumMeshes = 1;
  body->mMeshes = new unsigned[1]{0};
  children[joints] = {nodes[0], body};
  for (int j = 1; j < joints; ++j) children[skeleton.joint(j).parent].push_back(nodes[j]);
  for (int j = 0; j <= joints; ++j) {
    aiNode* parent = j == joints ? scene->mRootNode : nodes[j];
    if (children[j].empty()) continue;
    parent->mNumChildren = static_cast<unsigned>(children[j].size());
    parent->mChildren = new aiNode*[children[j].size()];
    for (size_t k = 0; k < children[j].size(); ++k) {
      parent->mChildren[k] = children[j][k];
      children[j][k]->mParent = parent;
    }
  }
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial* [1] { new aiMaterial };
  auto* m = new aiMesh;
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh* [1] { m };
  m->mName = "body";
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const int n = mesh.rest.vertexCount();
  m->mNumVertices = static_cast<unsigned>(n);
  m->mVertices = new aiVector3D[n];
  m->mNormals = new aiVector3D[n];
  for (int v = 0; v < n; ++v) {
    m->mVertices[v] = toAi(to_file * mesh.rest.positions.col(v));
    m->mNormals[v] = toAi((to_file * mesh.rest.normals.col(v)).normalized());
  }
  const bool mirror = to_file.determinant() < 0;
  m->mNumFaces = static_cast<unsigned>(mesh.rest.triangles.size());
  m->mFaces = new aiFace[m->mNumFaces];
  for (size_t t = 0; t < mesh.rest.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.rest.triangles[t];
    m->mFaces[t].mNumIndices = 3;
    m->mFaces[t].mIndices =
        new unsigned[3]{static_cast<unsigned>(tri[0]), static_cast<unsigned>(tri[mirror ? 2 : 1]),
                        static_cast<unsigned>(tri[mirror ? 1 : 2])};
  }
  std::vector<std::vector<aiVertexWeight>> weights(joints);
  for (int v = 0; v < n; ++v) {
    for (int k = 0; k < kMaxInfluences; ++k) {
      if (mesh.skin.weights[v][k] > 0)
        weights[mesh.skin.joints[v][k]].emplace_back(v, mesh.skin.weights[v][k]);
    }
  }
  m->mNumBones = static_cast<unsigned>(joints);
  m->mBones = new aiBone*[joints];
  for (int j = 0; j < joints; ++j) {
    auto* bone = new aiBone;
    bone->mName = skeleton.joint(j).name;
    bone->mOffsetMatrix = translation(-(to_file * skeleton.restPositions()[j].cast<float>()));
    bone->mNumWeights = static_cast<unsigned>(weights[j].size());
    bone->mWeights = new aiVertexWeight[std::max<size_t>(weights[j].size(), 1)];
    std::copy(weights[j].begin(), weights[j].end(), bone->mWeights);
    m->mBones[j] = bone;
  }
  return scene;
}

// `mesh` in a file of Assimp's exporter `format` whose frame is `frame`.
void exportAs(const SkinnedMesh& mesh, const Frame& frame, const char* format,
              const fs::path& path) {
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(sceneOf(mesh, oursToFile(frame)).get(), format, path.string()),
            AI_SUCCESS)
      << exporter.GetErrorString();
}

void replaceOnce(std::string& text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// Sets values of an ASCII FBX file's GlobalSettings ("P: "UpAxis", "int", "Integer", "", 1").
void setFbxSettings(const fs::path& path,
                    const std::vector<std::pair<std::string, std::string>>& settings) {
  std::string text = readText(path);
  for (const auto& [name, value] : settings) {
    const size_t at = text.find("P: \"" + name + "\", ");
    ASSERT_NE(at, std::string::npos) << name;
    const size_t end = text.find('\n', at);
    const size_t last = text.rfind(", ", end);
    text.replace(last + 2, end - last - 2, value);
  }
  writeText(path, text);
}

// `mesh` as a DirectX .X text file with its skin (Assimp's exporter writes none), coordinates
// `to_file` times ours. Lists of numbers are separated by ", ": Assimp reads "1,0" as 1.0.
void writeX(const fs::path& path, const SkinnedMesh& mesh, const Eigen::Matrix3f& to_file) {
  std::ostringstream x;
  x << std::setprecision(9) << "xof 0303txt 0032\n";
  // Matrices are row-major for row vectors: the translation is the last row.
  const auto matrix = [&](const V3& t) {
    x << "FrameTransformMatrix {\n1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, " << t.x() << ", " << t.y()
      << ", " << t.z() << ", 1;;\n}\n";
  };
  const Skeleton& skeleton = mesh.skeleton;
  const auto frame = [&](auto&& self, int j) -> void {
    x << "Frame " << skeleton.joint(j).name << " {\n";
    matrix(to_file * skeleton.joint(j).offset_m.cast<float>());
    for (int k = j + 1; k < skeleton.jointCount(); ++k) {
      if (skeleton.joint(k).parent == j) self(self, k);
    }
    x << "}\n";
  };
  x << "Frame scene_root {\n";
  matrix(V3::Zero());
  frame(frame, 0);
  x << "Frame body {\n";
  matrix(V3::Zero());
  const int n = mesh.rest.vertexCount();
  const auto vectors = [&](const auto& of) {
    x << n << ";\n";
    for (int v = 0; v < n; ++v) {
      const V3 p = of(v);
      x << p.x() << ";" << p.y() << ";" << p.z() << ";" << (v + 1 < n ? "," : ";") << "\n";
    }
    const bool mirror = to_file.determinant() < 0;
    x << mesh.rest.triangles.size() << ";\n";
    for (size_t t = 0; t < mesh.rest.triangles.size(); ++t) {
      const Eigen::Vector3i& tri = mesh.rest.triangles[t];
      x << "3;" << tri[0] << ", " << tri[mirror ? 2 : 1] << ", " << tri[mirror ? 1 : 2] << ";"
        << (t + 1 < mesh.rest.triangles.size() ? "," : ";") << "\n";
    }
  };
  x << "Mesh body_mesh {\n";
  vectors([&](int v) -> V3 { return to_file * mesh.rest.positions.col(v); });
  x << "MeshNormals {\n";
  vectors([&](int v) -> V3 { return (to_file * mesh.rest.normals.col(v)).normalized(); });
  x << "}\nXSkinMeshHeader {\n4;\n12;\n" << skeleton.jointCount() << ";\n}\n";
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    std::vector<std::pair<int, float>> weights;
    for (int v = 0; v < n; ++v) {
      for (int k = 0; k < kMaxInfluences; ++k) {
        if (mesh.skin.joints[v][k] == j && mesh.skin.weights[v][k] > 0)
          weights.emplace_back(v, mesh.skin.weights[v][k]);
      }
    }
    x << "SkinWeights {\n\"" << skeleton.joint(j).name << "\";\n" << weights.size() << ";\n";
    for (size_t k = 0; k < weights.size(); ++k)
      x << weights[k].first << (k + 1 < weights.size() ? ", " : ";\n");
    for (size_t k = 0; k < weights.size(); ++k)
      x << weights[k].second << (k + 1 < weights.size() ? ", " : ";\n");
    const V3 rest = to_file * skeleton.restPositions()[j].cast<float>();
    x << "1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, " << -rest.x() << ", " << -rest.y() << ", "
      << -rest.z() << ", 1;;\n}\n";
  }
  x << "}\n}\n}\n";  // mesh, body, scene_root
  writeText(path, x.str());
}

// Six times the volume a closed mesh encloses: positive when its triangles face out.
double signedVolume(const TriangleMesh& mesh) {
  double sum = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    sum += mesh.positions.col(t[0]).cast<double>().dot(
        mesh.positions.col(t[1]).cast<double>().cross(mesh.positions.col(t[2]).cast<double>()));
  }
  return sum;
}

// `loaded` stands as `original` does, in our axes and metres: every joint (by name) where the
// original's is, under the same parent; every vertex, its normal and its weights (by joint name);
// the triangles facing out.
void expectStandsAsOriginal(const SkinnedMesh& original, const SkinnedMesh& loaded) {
  constexpr double kTolerance = 1e-4;  // metres
  const Skeleton& a = original.skeleton;
  const Skeleton& b = loaded.skeleton;
  ASSERT_EQ(b.jointCount(), a.jointCount());
  for (int j = 0; j < a.jointCount(); ++j) {
    const std::optional<int> k = b.findJoint(a.joint(j).name);
    ASSERT_TRUE(k) << a.joint(j).name;
    EXPECT_EQ(a.joint(j).parent < 0 ? "" : a.joint(a.joint(j).parent).name,
              b.joint(*k).parent < 0 ? "" : b.joint(b.joint(*k).parent).name);
    EXPECT_LT((a.restPositions()[j] - b.restPositions()[*k]).norm(), kTolerance)
        << a.joint(j).name << " at " << b.restPositions()[*k].transpose() << ", expected "
        << a.restPositions()[j].transpose();
  }
  const auto at = [&](const char* name) { return b.restPositions()[*b.findJoint(name)]; };
  EXPECT_GT(at("head").z() - at("left_foot").z(), 1.4) << "head above feet, in metres";
  EXPECT_LT(at("left_hip").x(), at("right_hip").x()) << "the actor's left at -x";
  EXPECT_GT(at("left_foot").y(), at("left_ankle").y()) << "toes forward, at +y";

  ASSERT_EQ(loaded.rest.vertexCount(), original.rest.vertexCount());
  for (int v = 0; v < original.rest.vertexCount(); ++v) {
    Eigen::Index w = 0;
    const float distance = (loaded.rest.positions.colwise() - original.rest.positions.col(v))
                               .colwise()
                               .norm()
                               .minCoeff(&w);
    ASSERT_LT(distance, kTolerance) << "vertex " << v;
    EXPECT_GT(loaded.rest.normals.col(w).dot(original.rest.normals.col(v)), 0.9999f)
        << "vertex " << v;
    std::map<std::string, float> expected, got;
    for (int k = 0; k < kMaxInfluences; ++k) {
      expected[a.joint(original.skin.joints[v][k]).name] += original.skin.weights[v][k];
      got[b.joint(loaded.skin.joints[w][k]).name] += loaded.skin.weights[w][k];
    }
    for (const auto& [name, weight] : expected)
      EXPECT_NEAR(got[name], weight, 1e-5) << "vertex " << v << " " << name;
  }
  EXPECT_NEAR(signedVolume(loaded.rest) / signedVolume(original.rest), 1, 1e-3);
}

TEST(MeshImport, EveryFormatStandsUpInMetres) {
  const fs::path folder = testFolder();
  const SkinnedMesh human = testing::makeHumanMesh();
  ASSERT_GT(signedVolume(human.rest), 0);
  const auto expectStands = [&](const fs::path& file) {
    SCOPED_TRACE(file.filename().string());
    LogCapture log;
    expectStandsAsOriginal(human, loadSkinnedMesh(file));
    EXPECT_EQ(log.text(), "");  // every format here says which way is up, and it agrees
  };

  exportAs(human, kGltf, "gltf2", folder / "human.gltf");
  expectStands(folder / "human.gltf");
  exportAs(human, kGltf, "glb2", folder / "human.glb");
  expectStands(folder / "human.glb");

  // COLLADA: Assimp applies <up_axis> and <unit>. Y up in metres, and Z up in centimetres
  // (Blender's and 3ds Max's axes: the actor facing -Y).
  exportAs(human, kGltf, "collada", folder / "human_y.dae");
  expectStands(folder / "human_y.dae");
  exportAs(human, {kX, -kY, kZ, 100}, "collada", folder / "human_z_cm.dae");
  std::string dae = readText(folder / "human_z_cm.dae");
  replaceOnce(dae, R"(<unit name="meter" meter="1" />)",
              R"(<unit name="centimeter" meter="0.01" />)");
  replaceOnce(dae, "<up_axis>Y_UP</up_axis>", "<up_axis>Z_UP</up_axis>");
  writeText(folder / "human_z_cm.dae", dae);
  expectStands(folder / "human_z_cm.dae");

  // FBX (ASCII: Assimp 5.2's binary FBX writer makes files its reader refuses). As Assimp writes
  // it: Maya's axes, centimetres (UnitScaleFactor 1).
  exportAs(human, {kX, kZ, kY, 100}, "fbxa", folder / "human_y_cm.fbx");
  expectStands(folder / "human_y_cm.fbx");
  // 3ds Max's axes (Z up, the actor facing -Y) in inches.
  exportAs(human, {kX, -kY, kZ, 1 / 0.0254f}, "fbxa", folder / "human_z_in.fbx");
  setFbxSettings(folder / "human_z_in.fbx", {{"UpAxis", "2"}, {"FrontAxis", "1"}});
  setFbxSettings(folder / "human_z_in.fbx", {{"FrontAxisSign", "-1"}, {"UnitScaleFactor", "2.54"}});
  expectStands(folder / "human_z_in.fbx");
  // Left-handed (CoordAxis -X), in metres.
  exportAs(human, {-kX, kZ, kY, 1}, "fbxa", folder / "human_lh_m.fbx");
  setFbxSettings(folder / "human_lh_m.fbx", {{"CoordAxisSign", "-1"}, {"UnitScaleFactor", "100"}});
  expectStands(folder / "human_lh_m.fbx");

  // DirectX .X: left-handed, Y up, the actor facing -Z (Assimp turns it into Assimp's axes by
  // negating z).
  const Eigen::Matrix3f left_handed = V3(1, 1, -1).asDiagonal();
  writeX(folder / "human.x", human, left_handed * oursToFile(kGltf));
  expectStands(folder / "human.x");
}

TEST(MeshImport, XFileWithZUpStandsUpByItsSkeleton) {
  // What exporters from Z-up tools write into .X files: our axes as they are (then negated z, as
  // Assimp undoes). Read as DirectX's Y up, the actor would lie on its back.
  const fs::path folder = testFolder();
  const SkinnedMesh human = testing::makeHumanMesh();
  const fs::path file = folder / "lying.x";
  writeX(file, human, V3(1, 1, -1).asDiagonal());
  LogCapture log;
  expectStandsAsOriginal(human, loadSkinnedMesh(file));
  const std::string said = log.text();
  EXPECT_NE(said.find(file.string() + ": a DirectX .X file is +Y up"), std::string::npos) << said;
  EXPECT_NE(said.find("standing it up by its skeleton (head above feet), +Z up, the actor facing "
                      "+Y"),
            std::string::npos)
      << said;
}

TEST(MeshImport, ABodyOfNoHumanSizeGetsAUnitsWarning) {
  // .X has no units: a file in inches comes in 39 times too tall, and says so (in centimetres it
  // would be refused: nothing is more than 100 m from the origin).
  const fs::path folder = testFolder();
  const SkinnedMesh human = testing::makeHumanMesh();
  const fs::path file = folder / "inches.x";
  writeX(file, human, V3(1, 1, -1).asDiagonal() * oursToFile({kX, kZ, kY, 1 / 0.0254f}));
  LogCapture log;
  const SkinnedMesh loaded = loadSkinnedMesh(file);
  const float height =
      loaded.rest.positions.row(2).maxCoeff() - loaded.rest.positions.row(2).minCoeff();
  EXPECT_GT(height, 50);
  EXPECT_NE(log.text().find(file.string() + ": the body stands "), std::string::npos) << log.text();
  EXPECT_NE(log.text().find(" m tall as read, expected 0.2 to 3 m: are its units"),
            std::string::npos)
      << log.text();
}

TEST(MeshImport, DeclaredAxesWinOverTheSkeletonWithAWarning) {
  // A glTF whose actor lies along +Z: glTF is +Y up by definition, so it stays lying, and says so.
  const fs::path folder = testFolder();
  const SkinnedMesh human = testing::makeHumanMesh();
  const fs::path file = folder / "lying.glb";
  exportAs(human, {-kX, kY, kZ, 1}, "glb2", file);  // our own axes
  LogCapture log;
  const SkinnedMesh loaded = loadSkinnedMesh(file);
  const Skeleton& s = loaded.skeleton;
  EXPECT_LT(std::abs(s.restPositions()[*s.findJoint("head")].z() -
                     s.restPositions()[*s.findJoint("left_foot")].z()),
            0.2);
  EXPECT_NE(log.text().find(file.string() + ": its skeleton stands along +Z (head above feet) but "
                                            "the file says +Y is up (glTF): following the file"),
            std::string::npos)
      << log.text();
}

TEST(MeshImport, BadFbxAxesGiveClearErrors) {
  const fs::path folder = testFolder();
  const SkinnedMesh human = testing::makeHumanMesh();
  using Settings = std::vector<std::pair<std::string, std::string>>;
  const std::vector<std::pair<Settings, std::string>> cases = {
      {{{"UpAxis", "5"}},
       "FBX GlobalSettings UpAxis 5 with UpAxisSign 1: expected an axis 0, 1 or 2"},
      {{{"FrontAxisSign", "0"}}, "FrontAxis 2 with FrontAxisSign 0"},
      {{{"UpAxis", "2"}}, "put UpAxis (+Z), FrontAxis (+Z) and CoordAxis (+X) on the same axis"},
      {{{"UnitScaleFactor", "-2.54"}}, "UnitScaleFactor -2.54: expected a positive number"},
      {{{"UnitScaleFactor", "nan"}}, "UnitScaleFactor nan"},
      {{{"UnitScaleFactor", "0"}}, "UnitScaleFactor must be non-zero"},  // Assimp's words
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const fs::path file = folder / ("bad" + std::to_string(i) + ".fbx");
    exportAs(human, {kX, kZ, kY, 100}, "fbxa", file);
    setFbxSettings(file, cases[i].first);
    const std::string m = testing::errorOf([&] { loadSkinnedMesh(file); });
    EXPECT_NE(m.find(file.string() + ": "), std::string::npos) << m;
    EXPECT_NE(m.find(cases[i].second), std::string::npos) << m;
  }
}

TEST(MeshImport, SkeletonAxesFromJointNames) {
  // A skeleton standing along `up` with its left side along `left` (both in file coordinates).
  const auto stand = [](const std::vector<std::string>& names, const V3& up, const V3& left) {
    const V3 at[] = {up, -up + left * 0.1f, -up - left * 0.1f, V3::Zero()};  // head, feet, hips
    std::vector<V3> positions;
    for (size_t j = 0; j < names.size(); ++j) positions.push_back(at[std::min<size_t>(j, 3)]);
    return skeletonAxes(names, positions);
  };
  const auto expectAxes = [&](const std::vector<std::string>& names, const V3& up, const V3& left) {
    SCOPED_TRACE(names[0] + " " + names[1]);
    const SkeletonAxes axes = stand(names, up, left);
    ASSERT_TRUE(axes.up);
    EXPECT_EQ(*axes.up, up);
    ASSERT_TRUE(axes.left);
    EXPECT_EQ(*axes.left, left);
  };
  expectAxes({"mixamorig:Head", "mixamorig:LeftFoot", "mixamorig:RightFoot", "mixamorig:Hips"}, kY,
             kX);
  expectAxes({"Bip01 Head", "Bip01 L Foot", "Bip01 R Foot", "Bip01 Pelvis"}, kZ, -kY);
  expectAxes({"head", "foot.L", "foot.R", "hips"}, -kX, kZ);
  expectAxes({"HeadTop_End", "LToeBase", "RToeBase", "Hips"}, kZ, kX);
  expectAxes({"Neck", "l_ankle", "r_ankle", "root"}, kY, -kZ);
  // Slightly off an axis (an A-pose, a lean) still snaps to it.
  {
    const SkeletonAxes axes = stand({"Head", "LeftFoot", "RightFoot"}, V3(0.3f, 1, 0.2f), kX);
    ASSERT_TRUE(axes.up);
    EXPECT_EQ(*axes.up, kY);
  }
  // Names that do not tell (CesiumMan's), or a skeleton between axes: nothing.
  EXPECT_FALSE(stand({"Skeleton_torso_joint_1", "leg_joint_L_5", "leg_joint_R_5"}, kY, kX).up);
  EXPECT_FALSE(stand({"Head", "LeftFoot", "RightFoot"}, V3(1, 1, 0), kZ).up);
  // Up without sides.
  const SkeletonAxes no_sides = stand({"Head", "Foot", "Toe"}, kZ, kX);
  ASSERT_TRUE(no_sides.up);
  EXPECT_EQ(*no_sides.up, kZ);
  EXPECT_FALSE(no_sides.left);
}

// The real CesiumMan (../shared/realdata/bodies, where present) loads as it always has: glTF's
// axes, no warning.
TEST(MeshImport, CesiumManStandsAsBefore) {
  const fs::path file = testing::realData() / "bodies" / "CesiumMan.glb";
  if (!fs::exists(file)) GTEST_SKIP() << file << " is not here";
  LogCapture log;
  const SkinnedMesh mesh = loadSkinnedMesh(file);
  EXPECT_EQ(log.text(), "");
  EXPECT_EQ(mesh.rest.vertexCount(), 2612);
  EXPECT_EQ(mesh.rest.triangles.size(), 4672u);
  EXPECT_EQ(mesh.skeleton.jointCount(), 19);
  const Eigen::Vector3f lo = mesh.rest.positions.rowwise().minCoeff();
  const Eigen::Vector3f hi = mesh.rest.positions.rowwise().maxCoeff();
  EXPECT_NEAR(lo.z(), 0, 1e-3);
  EXPECT_NEAR(hi.z(), 1.507, 1e-3);
  EXPECT_NEAR(hi.x(), 0.569, 1e-3);
  EXPECT_NEAR(lo.y(), -0.131, 1e-3);
  EXPECT_NEAR(hi.y(), 0.181, 1e-3);
  const Skeleton& s = mesh.skeleton;
  const Eigen::Vector3d neck = s.restPositions()[*s.findJoint("Skeleton_neck_joint_2")];
  EXPECT_NEAR(neck.z(), 1.190, 1e-3);
  EXPECT_NEAR(s.restPositions()[*s.findJoint("leg_joint_L_5")].x(), -0.085, 1e-3);
}

}  // namespace
}  // namespace lumistage
