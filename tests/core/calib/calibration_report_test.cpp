#include "core/calib/calibration_report.h"

#include <gtest/gtest.h>

#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(CalibrationReport, CoverageCountsWhereTheSamplesFell) {
  const Camera camera = makeRingRig(RingRigSpec{}).camera(0);  // 1024x768
  const std::vector<Eigen::Vector2d> observed = {{10, 10}, {20, 30}, {1020, 760}};
  const std::vector<Eigen::Vector2d> residuals = {{0.3, 0.4}, {0, 0}, {0, 0.5}};
  const CameraCalibrationReport r = makeCameraReport(camera, observed, residuals, 5, 4, 3);
  EXPECT_EQ(r.observations, 5);
  EXPECT_EQ(r.inliers, 3);
  EXPECT_NEAR(r.rms_px, 0.5 * std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_DOUBLE_EQ(r.max_px, 0.5);
  EXPECT_EQ(r.coverage, (std::vector<int>{2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}));
  EXPECT_DOUBLE_EQ(r.coverage_fraction, 2.0 / 12);
}

TEST(CalibrationReport, SavesAndLoadsBack) {
  CalibrationReport report;
  report.method = "wand";
  report.samples = 1000;
  report.metric = true;
  report.notes = {"a \"quoted\" note", "another"};
  const Rig rig = makeRingRig(RingRigSpec{});
  for (int c = 0; c < 2; ++c) {
    report.cameras.push_back(
        makeCameraReport(rig.camera(c), {{100, 100}, {500, 300}}, {{0.1, 0}, {0, 0.2}}, 3));
  }
  finishReport(report);
  const std::filesystem::path file = testing::testFolder("report") / "report.yaml";
  saveCalibrationReport(report, file);
  const CalibrationReport back = loadCalibrationReport(file);
  EXPECT_EQ(back.method, "wand");
  EXPECT_EQ(back.samples, 1000);
  EXPECT_TRUE(back.metric);
  EXPECT_EQ(back.notes, report.notes);
  ASSERT_EQ(back.cameras.size(), 2u);
  EXPECT_EQ(back.cameras[1].name, rig.camera(1).name());
  EXPECT_EQ(back.cameras[1].coverage, report.cameras[1].coverage);
  EXPECT_NEAR(back.cameras[1].rms_px, report.cameras[1].rms_px, 1e-4);
  EXPECT_NEAR(back.rms_px, report.rms_px, 1e-4);

  const std::string message = testing::errorOf([] {
    parseCalibrationReport("method: wand\nsamples: 3\nrms_px: x\ncameras: []\n", "r.yaml");
  });
  EXPECT_NE(message.find("r.yaml:3"), std::string::npos) << message;
  EXPECT_NE(message.find("rms_px"), std::string::npos) << message;
}

}  // namespace
}  // namespace lumistage
