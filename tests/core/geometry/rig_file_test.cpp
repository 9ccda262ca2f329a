#include "core/geometry/rig_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "tests/core/geometry/test_cameras.h"

namespace lumistage {
namespace {

// A small valid rig file; each bad-input test breaks one thing in it.
const std::string kGood = R"(format: lumistage-rig
version: 1
nodes:
  - name: node1
    host: "10.0.0.11"
    cameras: [camA, camB]
cameras:
  - name: camA
    image_size: [1024, 768]
    intrinsics: {fx: 800, fy: 801, cx: 511.5, cy: 383.5}
    distortion: {k1: -0.1, k2: 0.01, p1: 0, p2: 0, k3: 0}
    rotation:
      - [1, 0, 0]
      - [0, 1, 0]
      - [0, 0, 1]
    translation: [0, 0, 3]
  - name: camB
    image_size: [1024, 768]
    intrinsics: {fx: 800, fy: 800, cx: 511.5, cy: 383.5, skew: 0}
    rotation:
      - [0, 0, -1]
      - [0, 1, 0]
      - [1, 0, 0]
    translation: [0, 0, 3]
)";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string errorOf(const std::string& text) {
  try {
    parseRig(text, "bad.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(RigFile, ParsesTheDocumentedFormat) {
  const Rig rig = parseRig(kGood, "good.yaml");
  ASSERT_EQ(rig.cameraCount(), 2);
  ASSERT_EQ(rig.nodeCount(), 1);
  EXPECT_EQ(rig.nodes()[0].host, "10.0.0.11");
  EXPECT_EQ(rig.camera(1).node(), "node1");
  EXPECT_DOUBLE_EQ(rig.camera(0).intrinsics().fy, 801);
  EXPECT_DOUBLE_EQ(rig.camera(0).distortion().k1, -0.1);
  EXPECT_TRUE(rig.camera(1).distortion().isZero());  // distortion is optional
  EXPECT_EQ(rig.camera(1).centre(), Eigen::Vector3d(-3, 0, 0));
}

TEST(RigFile, SaveThenLoadGivesExactlyTheSameRig) {
  std::mt19937 rng(11);
  std::vector<Camera> cameras;
  for (int i = 0; i < 7; ++i) {
    cameras.push_back(
        testing::randomCamera(rng, i % 2 == 0, i % 3 == 0, "cam" + std::to_string(i)));
  }
  std::vector<RigNode> nodes = dealCamerasToNodes(7, 3);
  nodes[1].host = "stage-pc-2.local";
  Rig rig(cameras, nodes);
  rig.setStage(StageBox{{-2.05, -1.7, 0}, {1.95, 2.3, 2.45}});

  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("lumistage_rig_roundtrip_" + std::to_string(::getpid()) + ".yaml");
  saveRig(rig, path);
  const Rig loaded = loadRig(path);
  EXPECT_TRUE(loaded == rig);  // every double bit for bit
  EXPECT_EQ(formatRig(loaded), readFile(path));
  std::filesystem::remove(path);
}

TEST(RigFile, TheStageBoxIsOptional) {
  EXPECT_FALSE(parseRig(kGood, "good.yaml").stage());
  const Rig rig = parseRig(
      replaced(kGood, "nodes:", "stage: {lower: [-2, -1.5, 0], upper: [2, 1.5, 2.4]}\nnodes:"),
      "good.yaml");
  ASSERT_TRUE(rig.stage());
  EXPECT_EQ(rig.stage()->lower, Eigen::Vector3d(-2, -1.5, 0));
  EXPECT_EQ(rig.stage()->upper, Eigen::Vector3d(2, 1.5, 2.4));
  EXPECT_TRUE(nodeRig(rig, "node1").stage() == rig.stage());  // what a node records
}

TEST(RigFile, AStageBoxThatIsNoBoxIsRejected) {
  const auto withStage = [](const std::string& stage) {
    return errorOf(replaced(kGood, "nodes:", "stage: " + stage + "\nnodes:"));
  };
  std::string e = withStage("{lower: [2, -1.5, 0], upper: [-2, 1.5, 2.4]}");
  EXPECT_NE(e.find("bad.yaml:3: stage: the stage box [2, -1.5, 0] to [-2, 1.5, 2.4]: expected the "
                   "lower corner below the upper one"),
            std::string::npos)
      << e;
  e = withStage("{lower: [-2, -1.5, 1], upper: [2, 1.5, 2.4]}");
  EXPECT_NE(e.find("expected its floor at the stage's"), std::string::npos) << e;
  e = withStage("{lower: [-200, -150, 0], upper: [200, 150, 2.4]}");  // centimetres
  EXPECT_NE(e.find("expected at most 20 m a side"), std::string::npos) << e;
  e = withStage("{lower: [-2, -1.5, 0], upper: [2, 1.5, 0.9]}");  // nobody fits
  EXPECT_NE(e.find("expected it 1.5 to 5 m high"), std::string::npos) << e;
  e = withStage("{lower: [-2, -1.5], upper: [2, 1.5, 2.4]}");
  EXPECT_NE(e.find("bad.yaml:3: stage.lower:"), std::string::npos) << e;
  e = withStage("{lower: [-2, -1.5, 0], upper: [2, 1.5, 2.4], centre: [0, 0, 0]}");
  EXPECT_NE(e.find("stage.centre"), std::string::npos) << e;
  e = withStage("{lower: [-2, -1.5, 0]}");
  EXPECT_NE(e.find("stage.upper: missing key 'upper'"), std::string::npos) << e;
}

TEST(RigFile, MissingFieldNamesKeyAndLine) {
  const std::string e = errorOf(replaced(kGood, "fx: 800, fy: 801, ", "fy: 801, "));
  EXPECT_NE(e.find("bad.yaml:10: cameras[0].intrinsics.fx: missing key 'fx'"), std::string::npos)
      << e;
}

TEST(RigFile, NonNumericValueNamesKeyLineAndValue) {
  const std::string e = errorOf(replaced(kGood, "cx: 511.5, cy: 383.5}\n    distortion",
                                         "cx: abc, cy: 383.5}\n    distortion"));
  EXPECT_NE(e.find("bad.yaml:10: cameras[0].intrinsics.cx: expected a finite number, got 'abc'"),
            std::string::npos)
      << e;
}

TEST(RigFile, NegativeFocalLengthIsRejected) {
  const std::string e = errorOf(replaced(kGood, "fx: 800, fy: 801", "fx: -800, fy: 801"));
  EXPECT_NE(e.find("bad.yaml:10: cameras[0].intrinsics.fx: expected a positive focal length in "
                   "pixels, got -800"),
            std::string::npos)
      << e;
}

TEST(RigFile, SingularRotationIsRejected) {
  const std::string e =
      errorOf(replaced(kGood, "- [0, 0, 1]\n    translation: [0, 0, 3]\n  - name: camB",
                       "- [0, 0, 0]\n    translation: [0, 0, 3]\n  - name: camB"));
  EXPECT_NE(e.find("bad.yaml:13: cameras[0].rotation: expected a rotation matrix"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("(singular)"), std::string::npos) << e;
}

TEST(RigFile, NonRotationMatrixIsRejected) {
  const std::string e = errorOf(replaced(kGood, "- [1, 0, 0]\n      - [0, 1, 0]\n      - [0, 0, 1]",
                                         "- [1, 0.2, 0]\n      - [0, 1, 0]\n      - [0, 0, 1]"));
  EXPECT_NE(e.find("cameras[0].rotation: expected a rotation matrix"), std::string::npos) << e;
  const std::string reflection =
      errorOf(replaced(kGood, "- [0, 0, 1]\n    translation: [0, 0, 3]\n  - name: camB",
                       "- [0, 0, -1]\n    translation: [0, 0, 3]\n  - name: camB"));
  EXPECT_NE(reflection.find("got a reflection"), std::string::npos) << reflection;
}

TEST(RigFile, UnknownCameraReferencedByNodeIsRejected) {
  const std::string e = errorOf(replaced(kGood, "cameras: [camA, camB]", "cameras: [camA, camC]"));
  EXPECT_NE(e.find("bad.yaml:6: nodes[0].cameras[1]: node 'node1' refers to unknown camera 'camC'"),
            std::string::npos)
      << e;
}

TEST(RigFile, CameraInNoNodeOrTwoNodesIsRejected) {
  const std::string orphan = errorOf(replaced(kGood, "cameras: [camA, camB]", "cameras: [camA]"));
  EXPECT_NE(orphan.find("camera 'camB' belongs to no node"), std::string::npos) << orphan;
  const std::string twice =
      errorOf(replaced(kGood, "cameras: [camA, camB]", "cameras: [camA, camB, camA]"));
  EXPECT_NE(twice.find("camera 'camA' is already owned by node 'node1'"), std::string::npos)
      << twice;
}

TEST(RigFile, TruncatedFileIsRejectedWithItsName) {
  // Cut anywhere and the file is either a syntax error or misses what comes after the cut.
  for (size_t cut : {kGood.size() / 5, kGood.size() / 2, kGood.size() - 60, kGood.size() - 12}) {
    const std::string e = errorOf(kGood.substr(0, cut));
    EXPECT_EQ(e.rfind("bad.yaml", 0), 0u) << "cut at " << cut << ": " << e;
    EXPECT_NE(e, "no error");
  }
  const std::string mid_flow =
      errorOf(replaced(kGood, "translation: [0, 0, 3]\n  - name: camB", "translation: [0, 0,"));
  EXPECT_NE(mid_flow.find("YAML syntax error"), std::string::npos) << mid_flow;
}

TEST(RigFile, OtherMistakesGetTheirOwnMessages) {
  EXPECT_NE(errorOf("").find("bad.yaml: the file is empty"), std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "format: lumistage-rig", "format: something-else"))
                .find("not a Lumistage rig file"),
            std::string::npos);
  EXPECT_NE(
      errorOf(replaced(kGood, "version: 1", "version: 7")).find("written by a newer Lumistage"),
      std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "skew: 0", "skwe: 0")).find("unknown key 'skwe'"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "image_size: [1024, 768]", "image_size: [1024]"))
                .find("cameras[0].image_size: expected a list of 2, got 1 entries"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "image_size: [1024, 768]", "image_size: [1024.5, 768]"))
                .find("expected a whole number, got '1024.5'"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "- name: camB", "- name: camA"))
                .find("camera 'camA' is already defined as cameras[0]"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "fx: 800, fy: 801", "fx: .nan, fy: 801"))
                .find("expected a finite number"),
            std::string::npos);
  // A host the rig file could not be written back with (the session's rig.yaml would not parse).
  EXPECT_NE(errorOf(replaced(kGood, "host: \"10.0.0.11\"", "host: 'pc\"1'"))
                .find("host: expected a host name or address (letters, digits, '.', '-', ':', "
                      "'_'), got 'pc\"1'"),
            std::string::npos);
}

TEST(RigFile, MissingFileNamesThePath) {
  try {
    loadRig("/nonexistent/rig.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rig.yaml: cannot open"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lumistage
