#include "core/calib/multicamselfcal_files.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>

#include "core/calib/similarity.h"
#include "core/calib/wand_calibration.h"
#include "core/calib/wand_simulation.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

// MultiCamSelfCal's result is in its own gauge (its frame, its scale). Emulated here by the true
// rig moved by an arbitrary similarity and written as the toolbox writes it; imported through
// rig_import, it must agree with our own solve of the same simulated session.
TEST(MultiCamSelfCal, ImportedResultAgreesWithOurSolve) {
  const Rig truth = makeRingRig(RingRigSpec{});
  WandSimulationOptions sim;
  sim.samples = 300;
  sim.seed = 17;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  const std::filesystem::path folder = testing::testFolder("mcsc");
  writeMultiCamSelfCalInput(s.session, folder / "input");

  Similarity toolbox_gauge;
  toolbox_gauge.scale = 0.37;
  toolbox_gauge.R =
      Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  toolbox_gauge.t = {0.4, -1.2, 2.0};
  writeMultiCamSelfCalOutput(toolbox_gauge.apply(truth), folder / "output");
  RigImportOptions import_options;
  import_options.width = 1024;
  import_options.height = 768;
  const RigImport imported = importSvobodaRig(folder / "output", import_options);
  ASSERT_EQ(imported.rig.cameraCount(), 12);

  const WandCalibrationResult ours = calibrateWand(s.session, WandCalibrationOptions{});
  // Compared in our (metric) frame: the toolbox's rig aligned onto ours.
  const RigComparison cmp = compareRigs(imported.rig, ours.rig);
  EXPECT_NEAR(cmp.alignment.scale, 1 / 0.37, 0.01);
  // 300 samples: within a centimetre (the 5 mm target needs about 1000, see docs/calibration.md).
  EXPECT_LT(cmp.max_centre_m, 0.01);
  EXPECT_LT(cmp.max_rotation_deg, 0.1);
  EXPECT_LT(cmp.max_focal_rel, 0.005);
  // Focal length and lens together: the same rays land within a pixel where there were samples.
  for (const Camera& c : ours.rig.cameras()) {
    const int k = *s.session.findCamera(c.name());
    std::vector<Eigen::Vector2d> seen;
    for (int sp = 0; sp < s.session.sampleCount(); ++sp) {
      if (s.session.has(sp, k) && !s.outlier[sp][k]) seen.push_back(s.session.pixel(sp, k));
    }
    EXPECT_LT(
        intrinsicsDifferencePx(imported.rig.camera(*imported.rig.findCamera(c.name())), c, seen),
        1.0)
        << c.name();
  }

  // The toolbox's input: one row triple per camera, a column per sample.
  std::ifstream ids(folder / "input" / "IdMat.dat");
  std::string line;
  int rows = 0;
  while (std::getline(ids, line)) {
    ++rows;
    EXPECT_EQ(static_cast<int>(line.size()), 2 * s.session.sampleCount() - 1);
  }
  EXPECT_EQ(rows, 12);
}

}  // namespace
}  // namespace lumistage
