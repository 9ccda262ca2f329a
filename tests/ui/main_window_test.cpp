// The studio's main window under Qt's offscreen platform.
#include "ui/main_window.h"

#include <QDockWidget>
#include <QImage>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QtTest>

#include "core/capture/session_writer.h"
#include "core/geometry/ring_rig.h"
#include "ui/camera_grid_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/stage_plan_view.h"

using lumistage::MainWindow;

class MainWindowTest : public QObject {
  Q_OBJECT

 private:
  const QString reference_ = QString(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml";

  // Pixels of a node's colour in the stage plan: cameras and their fields of view.
  static int pixelsNear(const QImage& image, const QColor& colour) {
    int count = 0;
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        const QColor c = image.pixelColor(x, y);
        if (std::abs(c.red() - colour.red()) + std::abs(c.green() - colour.green()) +
                std::abs(c.blue() - colour.blue()) <
            30) {
          ++count;
        }
      }
    }
    return count;
  }

  // A small Bayer session of a ring of 64x48 cameras; frame f is flat grey 40 f.
  static void writeSession(const QString& folder, int cameras, int cameras_per_node, double fps,
                           int frames) {
    lumistage::RingRigSpec spec;
    spec.cameras = cameras;
    spec.cameras_per_node = cameras_per_node;
    spec.width = 64;
    spec.height = 48;
    lumistage::SessionWriter writer(folder.toStdString(), lumistage::makeRingRig(spec),
                                    lumistage::PixelFormat::kBayerRggb8, fps, "test");
    lumistage::Image image;
    image.resize(lumistage::PixelFormat::kBayerRggb8, 64, 48);
    for (int f = 0; f < frames; ++f) {
      std::fill(image.pixels.begin(), image.pixels.end(), uint8_t(40 * f));
      writer.writeFrame(f, static_cast<int64_t>(f * 1e9 / fps),
                        std::vector<lumistage::ImageView>(cameras, image.view()));
    }
  }

 private slots:
  void opensTheReferenceRig() {
    MainWindow window;
    window.resize(1000, 800);
    window.show();
    QCOMPARE(window.openRig(reference_), QString());
    QVERIFY(window.rig() != nullptr);
    QCOMPARE(window.rig()->cameraCount(), 12);
    QTableWidget* table = window.rigPanel()->table();
    QCOMPARE(table->rowCount(), 12);
    QCOMPARE(table->item(0, 0)->text(), QString("cam01"));
    QCOMPARE(table->item(1, 1)->text(), QString("node2"));
    QCOMPARE(table->item(0, 11)->text(), QString("2.300"));
  }

  void stagePlanDrawsEveryNode() {
    MainWindow window;
    window.resize(1000, 800);
    window.show();
    const QImage empty = window.stagePlan()->grab().toImage();
    QCOMPARE(pixelsNear(empty, lumistage::StagePlanView::nodeColour(0)), 0);
    QCOMPARE(window.openRig(reference_), QString());
    const QImage plan = window.stagePlan()->grab().toImage();
    for (int node = 0; node < 4; ++node) {
      QVERIFY2(pixelsNear(plan, lumistage::StagePlanView::nodeColour(node)) > 100,
               qPrintable(QString("node %1 not drawn").arg(node)));
    }
  }

  void selectingACameraHighlightsIt() {
    MainWindow window;
    window.resize(1000, 800);
    window.show();
    QCOMPARE(window.openRig(reference_), QString());
    const QImage before = window.stagePlan()->grab().toImage();
    window.rigPanel()->table()->selectRow(4);
    const QImage after = window.stagePlan()->grab().toImage();
    const QColor node1 = lumistage::StagePlanView::nodeColour(0);  // cam05 is on node1
    QVERIFY(pixelsNear(after, node1) > pixelsNear(before, node1));
  }

  void previewsDecimateBayerIntoColour() {
    // A 8x8 Bayer image: R=200, G=100, B=50 everywhere.
    lumistage::Image bayer;
    bayer.resize(lumistage::PixelFormat::kBayerRggb8, 8, 8);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x)
        bayer.pixels[y * 8 + x] = (y % 2 == 0) ? (x % 2 == 0 ? 200 : 100) : (x % 2 == 0 ? 100 : 50);
    }
    const QImage preview = lumistage::SourceWorker::preview(bayer);
    QCOMPARE(preview.size(), QSize(2, 2));
    QCOMPARE(preview.pixelColor(1, 1), QColor(200, 100, 50));
  }

  void liveSessionShowsEveryCameraAndNoticesWhenFramesStop() {
    // A small recorded session of two cameras, replayed as the studio's source.
    QTemporaryDir dir;
    writeSession(dir.filePath("session"), 2, 2, 10.0, 5);
    MainWindow window;
    window.resize(900, 700);
    window.show();
    lumistage::SourceSpec source;
    QCOMPARE(lumistage::SourceSpec::parse("session:" + dir.filePath("session"), source), QString());
    window.startSource(source);
    lumistage::CameraGridPanel* grid = window.cameraGrid();
    QTRY_COMPARE_WITH_TIMEOUT(grid->camerasWithPictures(), 2, 5000);
    QCOMPARE(grid->state(0), QString("streaming"));
    QCOMPARE(window.rig()->cameraCount(), 2);
    // Frames stop: late within a second, lost within three.
    window.stopSource();
    QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("late"), 1500);
    QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("lost"), 3000);
  }

  void pipelinePanelRunsNodesAndShowsTheirHealth() {
    QTemporaryDir dir;
    writeSession(dir.filePath("session"), 4, 2, 20.0, 4);
    MainWindow window;
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    QVERIFY(window.pipeline()->running());
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= 10, 20000);
    const lumistage::RunReport report = window.pipeline()->lastReport();
    QCOMPARE(static_cast<int>(report.nodes.size()), 2);
    for (const auto& node : report.nodes) QVERIFY2(!node.lost, node.name.c_str());
    QCOMPARE(window.pipeline()->table()->rowCount(), 4);  // a row per camera
    QCOMPARE(window.pipeline()->table()->item(0, 1)->text(), QString("streaming"));
    window.pipeline()->stop();
    QVERIFY(!window.pipeline()->running());
  }

  void unknownSourceIsRefusedWithTheChoices() {
    lumistage::SourceSpec spec;
    QVERIFY(lumistage::SourceSpec::parse("webcam", spec)
                .contains("expected virtual[:CONFIG], session:DIR"));
  }

  void badRigKeepsThePreviousOneAndSaysWhy() {
    QTemporaryDir dir;
    const QString bad = dir.filePath("bad.yaml");
    QFile file(bad);
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write("format: lumistage-rig\nversion: 1\ncameras: [\n");
    file.close();
    MainWindow window;
    QCOMPARE(window.openRig(reference_), QString());
    const QString error = window.openRig(bad);
    QVERIFY2(error.contains("bad.yaml") && error.contains("YAML syntax error"), qPrintable(error));
    QCOMPARE(window.rig()->cameraCount(), 12);
    QCOMPARE(window.rigPanel()->table()->rowCount(), 12);
  }
};

QTEST_MAIN(MainWindowTest)
#include "main_window_test.moc"
