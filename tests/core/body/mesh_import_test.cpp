// Rigged meshes from other tools: more than four influences per vertex (mesh_io.h).

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
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/body/mesh_io.h"
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

}  // namespace
}  // namespace lumistage
