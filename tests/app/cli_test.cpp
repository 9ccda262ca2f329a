// The command-line tools run as a user runs them: real processes, real files.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/geometry/rig_file.h"
#include "core/geometry/ring_rig.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code;
  std::string output;  // stdout and stderr together
};

Result run(const std::string& command) {
  Result result{-1, ""};
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

const std::string kCli = LUMISTAGE_CLI;
const std::string kNode = LUMISTAGE_NODE;
const std::string kReference = std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml";

fs::path tempPath(const std::string& name) {
  return fs::temp_directory_path() / ("lumistage_cli_" + std::to_string(::getpid()) + "_" + name);
}

TEST(Cli, RigShowListsCamerasNodesAndCentres) {
  const Result r = run(kCli + " rig show " + kReference);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 cameras on 4 nodes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("node node1"), std::string::npos);
  EXPECT_NE(r.output.find("cam12"), std::string::npos);
  EXPECT_NE(r.output.find("( 3.600,  0.000,  2.300)"), std::string::npos) << r.output;  // cam01
}

TEST(Cli, RigShowOfABadFileSaysWhereAndFails) {
  const fs::path bad = tempPath("bad.yaml");
  std::ofstream(bad) << "format: lumistage-rig\nversion: 1\nnodes: []\ncameras:\n  - name: c\n";
  const Result r = run(kCli + " rig show " + bad.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(
      r.output.find("lumistage: error: " + bad.string() + ":5: cameras[0].image_size: missing key"),
      std::string::npos)
      << r.output;
  fs::remove(bad);
}

TEST(Cli, RingThenImportOfSvobodaFilesRoundTrips) {
  // `rig ring` writes the reference rig; its cameras written out as MultiCamSelfCal files and
  // imported back give the same geometry.
  const fs::path ring = tempPath("ring.yaml");
  Result r = run(kCli + " rig ring --out " + ring.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Rig rig = loadRig(ring);
  EXPECT_TRUE(rig == makeRingRig({}));

  const fs::path folder = tempPath("svoboda");
  fs::create_directories(folder);
  for (int i = 0; i < rig.cameraCount(); ++i) {
    std::ofstream out(folder / ("camera" + std::to_string(i + 1) + ".Pmat.cal"));
    out.precision(17);
    const Eigen::Matrix<double, 3, 4> P = rig.camera(i).projectionMatrix();
    for (int row = 0; row < 3; ++row) out << P.row(row) << "\n";
  }
  const fs::path imported = tempPath("imported.yaml");
  r = run(kCli + " rig import --svoboda " + folder.string() + " --image-size 1024x768 --out " +
          imported.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: camera1: no .rad file"), std::string::npos) << r.output;
  const Rig back = loadRig(imported);
  ASSERT_EQ(back.cameraCount(), 12);
  for (int i = 0; i < 12; ++i) {
    EXPECT_LT((back.camera(i).centre() - rig.camera(i).centre()).norm(), 1e-9);
    EXPECT_EQ(back.nodeOfCamera(i), rig.nodeOfCamera(i));
  }

  r = run(kCli + " rig import --svoboda " + folder.string() + " --image-size 1024 --out " +
          imported.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("expected WIDTHxHEIGHT"), std::string::npos) << r.output;
  fs::remove_all(folder);
  fs::remove(ring);
  fs::remove(imported);
}

TEST(Cli, NodeChecksItsPlaceInTheRig) {
  Result r = run(kNode + " --rig " + kReference + " --node node2");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // valid, but nothing to serve in this build
  EXPECT_NE(r.output.find("node node2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cam02"), std::string::npos);
  EXPECT_NE(r.output.find("cam06"), std::string::npos);
  r = run(kNode + " --rig " + kReference + " --node node9");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no node 'node9'; the rig's nodes are: node1, node2, node3, node4"),
            std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace lumistage
