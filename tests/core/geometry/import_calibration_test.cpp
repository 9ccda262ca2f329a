#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/geometry/rig_file.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

const fs::path kSeeds = fs::path(LUMISTAGE_TEST_RESOURCE_DIR) / ".." / "tests" / "fuzz" / "seeds";

// Each calibration is read as its own importer reads it: the same cameras, whatever the path.
TEST(ImportCalibration, ReadsEachFormatByWhatItIs) {
  const fs::path folder = testing::testFolder("calibration");
  const Rig ring = makeRingRig({});
  saveRig(ring, folder / "rig.yaml");
  const RigImport rig = importCalibration(folder / "rig.yaml", {});
  EXPECT_EQ(rig.rig.cameraCount(), ring.cameraCount());
  EXPECT_EQ(rig.rig.nodes().size(), ring.nodes().size());  // a rig file keeps its own nodes

  const RigImportOptions options;
  const auto same = [](const Rig& a, const Rig& b) {
    ASSERT_EQ(a.cameraCount(), b.cameraCount());
    for (int c = 0; c < a.cameraCount(); ++c) {
      EXPECT_EQ(a.camera(c).name(), b.camera(c).name());
      EXPECT_TRUE(a.camera(c).centre().isApprox(b.camera(c).centre())) << a.camera(c).name();
    }
  };
  same(importCalibration(kSeeds / "Calib.qca.txt", options).rig,
       importQualisysRig(kSeeds / "Calib.qca.txt", options).rig);
  same(importCalibration(kSeeds / "Calib.toml", options).rig,
       importTomlRig(kSeeds / "Calib.toml", options).rig);
  same(importCalibration(kSeeds / "opencv_rig.yaml", options).rig,
       importOpenCvRig(kSeeds / "opencv_rig.yaml", options).rig);
  same(importCalibration(kSeeds / "opencv_rig.xml", options).rig,
       importOpenCvRig(kSeeds / "opencv_rig.xml", options).rig);
}

TEST(ImportCalibration, RefusesWhatItCannotTellNamingIt) {
  const fs::path folder = testing::testFolder("calibration");
  std::ofstream(folder / "cameras.csv") << "x,y\n";
  std::string e = testing::errorOf([&] { importCalibration(folder / "cameras.csv", {}); });
  EXPECT_NE(e.find("cameras.csv: not a calibration Lumistage reads"), std::string::npos) << e;
  e = testing::errorOf([&] { importCalibration(folder, {}); });
  EXPECT_NE(e.find("a folder of no calibration"), std::string::npos) << e;
  e = testing::errorOf([&] { importCalibration(folder / "missing.toml", {}); });
  EXPECT_NE(e.find("missing.toml: no such file"), std::string::npos) << e;
}

}  // namespace
}  // namespace lumistage
