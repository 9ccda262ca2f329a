// The main window's calibration panel: the epipolar check and the calibration report.
#include "ui/calibration_panel.h"

#include <QFile>
#include <QLabel>
#include <QTemporaryDir>
#include <QtTest>

#include "core/calib/calibration_report.h"
#include "core/geometry/epipolar.h"
#include "tests/ui/main_window_test.h"
#include "ui/main_window.h"
#include "ui/source_worker.h"

using lumistage::MainWindow;

void MainWindowTest::calibrationCheckDrawsEpipolarLinesThroughTheSamePoint() {
  MainWindow window;
  QCOMPARE(window.openRig(reference_), QString());
  lumistage::CalibrationPanel* cal = window.calibration();
  QCOMPARE(cal->cameraCount(), 12);
  const Eigen::Vector3d point(0.2, -0.1, 1.4);
  const auto pixel = window.rig()->camera(0).project(point);
  QVERIFY(pixel.has_value());
  QVERIFY(cal->pickPoint(0, *pixel));
  QVERIFY(cal->cameraView(0)->marker().has_value());
  int crossing = 0;
  for (int c = 1; c < 12; ++c) {
    const auto& curves = cal->cameraView(c)->curves();
    QCOMPARE(curves.size(), size_t(1));
    const auto seen = window.rig()->camera(c).project(point);
    if (seen && window.rig()->camera(c).inImage(*seen)) {
      QVERIFY(lumistage::distanceToPolyline(curves[0], *seen) < 1.0);
      ++crossing;
    }
  }
  QVERIFY(crossing >= 8);
}

void MainWindowTest::calibrationReportGivesReprojectionErrors() {
  QTemporaryDir dir;
  QFile file(dir.filePath("report.json"));
  QVERIFY(file.open(QIODevice::WriteOnly));
  file.write(R"({"cameras": [{"name": "cam01", "rms_px": 0.25}, {"camera": "cam02",
              "reprojection_error_px": 0.5}]})");
  file.close();
  lumistage::ReprojectionErrors errors;
  QCOMPARE(lumistage::loadCalibrationReport(dir.filePath("report.json"), errors), QString());
  QCOMPARE(errors.value("cam02"), 0.5);
  QFile bad(dir.filePath("bad.json"));
  QVERIFY(bad.open(QIODevice::WriteOnly));
  bad.write(R"({"cameras": [{"name": "cam01"}]})");
  bad.close();
  QVERIFY(lumistage::loadCalibrationReport(dir.filePath("bad.json"), errors).contains("rms_px"));

  // A bad report beside the rig is said, and still said once a source has opened.
  QVERIFY(QFile::copy(reference_, dir.filePath("stage.yaml")));
  QVERIFY(QFile::copy(dir.filePath("bad.json"), dir.filePath("calibration_report.json")));
  MainWindow window;
  QCOMPARE(window.openRig(dir.filePath("stage.yaml")), QString());
  auto* status = window.findChild<QLabel*>("status");
  QVERIFY2(status->text().contains("Calibration report ignored"), qPrintable(status->text()));
  lumistage::SourceSpec spec;
  QVERIFY(lumistage::SourceSpec::parse("virtual", spec).isEmpty());
  window.startSource(spec);
  QTRY_VERIFY_WITH_TIMEOUT(status->text().contains("cameras on"), 20000);
  QVERIFY2(status->text().contains("Calibration report ignored"), qPrintable(status->text()));
  window.stopSource();

  // The report `lumistage calibrate` writes beside the rig it solved is the one read.
  lumistage::CalibrationReport solved;
  solved.method = "wand";
  solved.cameras.push_back({});
  solved.cameras.back().name = "cam03";
  solved.cameras.back().rms_px = 0.31;
  solved.cameras.back().width = 1024, solved.cameras.back().height = 768;
  solved.cameras.back().coverage_cols = solved.cameras.back().coverage_rows = 1;
  solved.cameras.back().coverage = {40};
  lumistage::saveCalibrationReport(solved, dir.filePath("stage.calibration.yaml").toStdString());
  MainWindow second;
  QCOMPARE(second.openRig(dir.filePath("stage.yaml")), QString());
  QCOMPARE(second.calibration()->cameraView(2)->caption(),
           QString("cam03: reprojection error 0.31 px"));
  QCOMPARE(second.calibration()->cameraView(0)->caption(),
           QString("cam01: reprojection error not measured"));
  QVERIFY(!second.findChild<QLabel*>("status")->text().contains("ignored"));
}
