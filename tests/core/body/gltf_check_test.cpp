#include "core/body/gltf_check.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/base/error.h"
#include "core/body/mesh_io.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

// A glTF 2 document whose nodes form a chain `depth` deep, and a JSON array `json_depth` deep in
// the asset's extras.
std::string chainGltf(int depth, int json_depth = 1) {
  std::string text = R"({"asset": {"version": "2.0", "extras": )" + std::string(json_depth, '[') +
                     std::string(json_depth, ']') + R"(}, "scenes": [{"nodes": [0]}], "nodes": [)";
  for (int n = 0; n < depth; ++n) {
    text += n > 0 ? ", " : "";
    text += "{\"name\": \"n" + std::to_string(n) + "\"";
    if (n + 1 < depth) text += ", \"children\": [" + std::to_string(n + 1) + "]";
    text += "}";
  }
  return text + "]}";
}

std::string errorOfJson(const std::string& json) {
  return testing::errorOf([&] { checkGltfJsonNesting(json, "x.gltf"); });
}

TEST(GltfCheck, ShallowFilesPass) {
  EXPECT_NO_THROW(checkGltfJsonNesting(chainGltf(1000, 500), "x.gltf"));
  EXPECT_NO_THROW(checkGltfJsonNesting("{\"nodes\": [{}, {}], \"children\": [[[0]]]}", "x.gltf"));
  EXPECT_NO_THROW(checkGltfJsonNesting("not json at all ]]]", "x.gltf"));
  // glTF 1: nodes in an object, children by name.
  EXPECT_NO_THROW(checkGltfJsonNesting(
      R"({"nodes": {"a": {"children": ["b"]}, "b": {"children": []}}})", "x.gltf"));
}

TEST(GltfCheck, DeepNodesAndJsonAreRefused) {
  std::string m = errorOfJson(chainGltf(30000));
  EXPECT_NE(m.find("x.gltf: its nodes nest deeper than 1000 levels"), std::string::npos) << m;
  m = errorOfJson(chainGltf(2, 100000));
  EXPECT_NE(m.find("x.gltf: its JSON nests arrays and objects deeper than 512 levels"),
            std::string::npos)
      << m;
  // Unclosed nesting is refused as deep nesting, not read to the end first.
  m = errorOfJson(std::string(1'000'000, '{'));
  EXPECT_NE(m.find("deeper than 512"), std::string::npos) << m;
  // glTF 1's names, escaped keys.
  std::string named = R"({"n\u006fdes": {)";
  for (int n = 0; n < 1500; ++n) {
    named += n > 0 ? ", " : "";
    named += "\"k" + std::to_string(n) + "\": {\"children\": [\"k" + std::to_string(n + 1) + "\"]}";
  }
  m = errorOfJson(named + "}}");
  EXPECT_NE(m.find("deeper than 1000"), std::string::npos) << m;
}

TEST(GltfCheck, NodeHierarchiesThatAreNoTreesAreRefused) {
  // Each node the child of the one before twice over: an importer copying a subtree per parent
  // makes 2^depth nodes.
  std::string m = errorOfJson(R"({"nodes": [{"children": [1, 1]}, {"children": [2, 2]}, {}]})");
  EXPECT_NE(m.find("node '1' is a child of node '0' and of node '0'"), std::string::npos) << m;
  m = errorOfJson(R"({"nodes": [{"children": [1]}, {"children": [2]}, {"children": [1]}]})");
  EXPECT_NE(m.find("a child of node '0' and of node '2'"), std::string::npos) << m;
  m = errorOfJson(R"({"nodes": [{}, {"children": [2]}, {"children": [1]}]})");
  EXPECT_NE(m.find("2 of its nodes are their own ancestors"), std::string::npos) << m;
}

TEST(GltfCheck, DeepFilesNeverReachAssimp) {
  // Assimp crashed (stack overflow) on a 30,000-deep node chain, as .gltf and as .glb.
  const fs::path folder = testing::testFolder("gltf_check");
  const std::string json = chainGltf(30000);
  std::ofstream(folder / "deep.gltf") << json;
  std::string m = testing::errorOf([&] { loadSkinnedMesh(folder / "deep.gltf"); });
  EXPECT_NE(m.find("deep.gltf: its nodes nest deeper than 1000 levels"), std::string::npos) << m;

  std::string padded = json + std::string((4 - json.size() % 4) % 4, ' ');
  auto le32 = [](uint32_t v) {
    return std::string{char(v & 0xff), char(v >> 8 & 0xff), char(v >> 16 & 0xff), char(v >> 24)};
  };
  std::ofstream(folder / "deep.glb", std::ios::binary)
      << "glTF" << le32(2) << le32(uint32_t(20 + padded.size())) << le32(uint32_t(padded.size()))
      << "JSON" << padded;
  m = testing::errorOf([&] { loadSkinnedMesh(folder / "deep.glb"); });
  EXPECT_NE(m.find("deep.glb: its nodes nest deeper than 1000 levels"), std::string::npos) << m;
}

}  // namespace
}  // namespace lumistage
