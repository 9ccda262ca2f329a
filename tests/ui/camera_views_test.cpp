// The main window's views of the rig and its cameras: the stage plan, the camera grid and its
// previews, the source that feeds them, and the overlay of the body on a camera's picture.
#include <QImage>
#include <QSignalSpy>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QThread>
#include <QtTest>
#include <atomic>

#include "core/geometry/rig_file.h"
#include "tests/ui/main_window_test.h"
#include "ui/camera_grid_panel.h"
#include "ui/camera_overlay_view.h"
#include "ui/main_window.h"
#include "ui/overlay_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/stage_plan_view.h"

using lumistage::MainWindow;

void MainWindowTest::stagePlanDrawsEveryNode() {
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

// The green floor is the rig's stage box: the floor its cameras cover, or the rig file's box.
void MainWindowTest::stagePlanDrawsTheRigsStage() {
  MainWindow window;
  window.resize(1000, 800);
  window.show();
  const QColor floor(0x2f, 0x7d, 0x3a);
  QCOMPARE(window.openRig(reference_), QString());
  const int covered = pixelsNear(window.stagePlan()->grab().toImage(), floor);
  QTemporaryDir dir;
  lumistage::Rig small = lumistage::loadRig(reference_.toStdString());
  small.setStage(lumistage::StageBox{{-1, -1, 0}, {1, 1, 2.4}});
  const QString path = dir.filePath("small.yaml");
  lumistage::saveRig(small, path.toStdString());
  QCOMPARE(window.openRig(path), QString());
  const int given = pixelsNear(window.stagePlan()->grab().toImage(), floor);
  // 2 x 2 m against 4.0 x 4.0 m at the same scale (the cameras set the plan's extent).
  QVERIFY2(given > 0 && std::abs(double(given) / covered - 4.0 / 16.0) < 0.05,
           qPrintable(QString("floor pixels %1 against %2").arg(given).arg(covered)));
}

void MainWindowTest::selectingACameraHighlightsIt() {
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

void MainWindowTest::previewsDecimateBayerIntoColour() {
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

// The previews' silhouettes where the source says better than the picture's green: a frame's own
// mask from another tool, else the camera's clean plate; neither, no mask (keyed green).
void MainWindowTest::previewMasksComeFromTheFramesMaskOrItsPlate() {
  lumistage::CameraFrame frame;
  frame.image.resize(lumistage::PixelFormat::kRgb8, 16, 8);
  std::fill(frame.image.pixels.begin(), frame.image.pixels.end(), uint8_t(120));  // a grey wall
  QVERIFY(lumistage::SourceWorker::previewMask(frame, nullptr).isNull());
  lumistage::BackgroundModel plate(16, 8);
  plate.add(frame.image.view());
  plate.learn();
  uint8_t* actor = &frame.image.pixels[3 * (4 * 16 + 8)];  // pixel (8, 4): preview pixel (2, 1)
  actor[0] = 200, actor[1] = 40, actor[2] = 40;
  const QImage keyed = lumistage::SourceWorker::previewMask(frame, &plate);
  QCOMPARE(keyed.size(), QSize(4, 2));
  QCOMPARE(qGray(keyed.pixel(2, 1)), 255);
  QCOMPARE(qGray(keyed.pixel(1, 1)), 0);
  // The frame's own mask wins over the plate.
  frame.mask.assign(16 * 8, 0);
  frame.mask[0] = 255;  // pixel (0, 0): preview pixel (0, 0)
  const QImage masked = lumistage::SourceWorker::previewMask(frame, &plate);
  QCOMPARE(qGray(masked.pixel(0, 0)), 255);
  QCOMPARE(qGray(masked.pixel(2, 1)), 0);
}

void MainWindowTest::liveSessionShowsEveryCameraAndNoticesWhenFramesStop() {
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
  // Frames stop: late after half a second, lost after one, as the camera health panel says.
  window.stopSource();
  QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("late"), 1500);
  QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("lost"), 1200);
}

void MainWindowTest::theSourceSendsEveryFrameOfTheWatchedCamera() {
  QTemporaryDir dir;
  writeSession(dir.filePath("session"), 3, 3, 30.0, 6);
  lumistage::SourceSpec spec;
  QCOMPARE(lumistage::SourceSpec::parse("session:" + dir.filePath("session"), spec), QString());
  lumistage::SourceWorker worker(spec);
  worker.watchCamera(1);
  QVector<qint64> watched, previewed;
  int other_camera_watched = 0;
  std::atomic<int> watched_count{0};
  connect(&worker, &lumistage::SourceWorker::watchedFrame, &worker,
          [&](int camera, const QImage&, qint64 frame) {
            (camera == 1 ? watched.push_back(frame) : void(++other_camera_watched));
            ++watched_count;
          });
  connect(&worker, &lumistage::SourceWorker::frame, &worker,
          [&](int camera, const QImage&, qint64 frame) {
            if (camera == 1) previewed.push_back(frame);
          });
  QThread thread;
  worker.moveToThread(&thread);
  connect(&thread, &QThread::started, &worker, &lumistage::SourceWorker::run);
  thread.start();
  // Direct connections: the lambdas run on the worker's thread; what they kept is read here once
  // it has ended.
  QTRY_VERIFY_WITH_TIMEOUT(watched_count >= 20, 20000);
  worker.stop();
  thread.quit();
  QVERIFY(thread.wait(5000));
  QCOMPARE(other_camera_watched, 0);
  for (int i = 1; i < watched.size(); ++i) QVERIFY(watched[i] > watched[i - 1]);
  // The previews of camera 1 are some of its frames, a few a second.
  QVERIFY2(previewed.size() < watched.size(),
           qPrintable(QString("%1 against %2").arg(previewed.size()).arg(watched.size())));
  for (qint64 frame : previewed) QVERIFY(watched.contains(frame));
}

void MainWindowTest::overlayShowsTheChosenCamera() {
  MainWindow window;
  QCOMPARE(window.openRig(reference_), QString());
  lumistage::OverlayPanel* overlay = window.overlay();
  QVERIFY(overlay->selectCamera(5));
  QCOMPARE(overlay->view()->camera().name(), std::string("cam06"));
  QVERIFY(!overlay->selectCamera(12));
  // The silhouette is keyed from the green screen.
  QImage image(4, 1, QImage::Format_RGB888);
  image.setPixelColor(0, 0, QColor(40, 150, 60));    // screen
  image.setPixelColor(1, 0, QColor(180, 140, 120));  // skin
  const QImage mask = lumistage::CameraOverlayView::keySilhouette(image);
  QCOMPARE(qAlpha(mask.pixel(0, 0)), 0);
  QVERIFY(qAlpha(mask.pixel(1, 0)) > 0);
}

// While a pipeline runs, the silhouette layer is what the chosen camera's node keyed for the
// frame shown (on a stage with no green screen the picture's green key would take the whole room
// for the actor); without the nodes' silhouettes, the picture's green key again.
void MainWindowTest::overlayShowsTheSilhouetteItsNodeKeyed() {
  MainWindow window;
  QCOMPARE(window.openRig(reference_), QString());
  lumistage::OverlayPanel* overlay = window.overlay();
  QVERIFY(overlay->selectCamera(2));
  QImage room(8, 6, QImage::Format_RGB888);
  room.fill(QColor(150, 130, 110));  // a wall: no green, so all of it "actor" to a green key
  overlay->showWatchedFrame(2, room, 40);
  lumistage::PipelineSnapshot snapshot;
  snapshot.pose_frame = 40;
  auto keyed = std::make_shared<std::vector<lumistage::LowResSilhouette>>(2);
  for (int k = 0; k < 2; ++k) (*keyed)[k].reset(k == 0 ? 1 : 2, 4, 1024, 768);
  (*keyed)[1].set(100, 50);
  snapshot.silhouettes = keyed;
  overlay->showSnapshot(snapshot);
  lumistage::CameraOverlayView* view = overlay->view();
  QVERIFY(view->showsNodeSilhouette());
  QCOMPARE(view->silhouetteMask().size(), QSize(256, 192));
  QVERIFY(qAlpha(view->silhouetteMask().pixel(100, 50)) > 0);
  QCOMPARE(qAlpha(view->silhouetteMask().pixel(10, 10)), 0);
  // Another camera: its node's own silhouette (empty here), not camera 2's.
  QVERIFY(overlay->selectCamera(1));
  QCOMPARE(qAlpha(view->silhouetteMask().pixel(100, 50)), 0);
  // No silhouettes from the nodes: the picture's green key, which takes all of the room.
  QVERIFY(overlay->selectCamera(2));
  overlay->showSnapshot(lumistage::PipelineSnapshot{});
  QVERIFY(!view->showsNodeSilhouette());
  QCOMPARE(view->silhouetteMask().size(), room.size());
  QVERIFY(qAlpha(view->silhouetteMask().pixel(0, 0)) > 0);
  // ...unless the source keyed the picture itself (its masks, its plate).
  QImage mask(room.size(), QImage::Format_Grayscale8);
  mask.fill(0);
  mask.setPixel(3, 2, 255);
  overlay->showWatchedFrame(2, room, 41, mask);
  lumistage::PipelineSnapshot later;
  later.pose_frame = 41;
  overlay->showSnapshot(later);
  QCOMPARE(qAlpha(view->silhouetteMask().pixel(0, 0)), 0);
  QVERIFY(qAlpha(view->silhouetteMask().pixel(3, 2)) > 0);
}

// The body placed for a frame is drawn over that frame's own picture: the chosen camera's every
// frame reaches the overlay, a few a second (4) reach it for the others, and a frame that comes
// by both ways is kept once.
void MainWindowTest::overlayDrawsTheBodyOverThePictureOfItsFrame() {
  MainWindow window;
  QCOMPARE(window.openRig(reference_), QString());
  lumistage::OverlayPanel* overlay = window.overlay();
  QSignalSpy selected(overlay, &lumistage::OverlayPanel::cameraSelected);
  QVERIFY(overlay->selectCamera(3));
  QCOMPARE(selected.size(), 1);
  QCOMPARE(selected.front().front().toInt(), 3);
  const auto picture = [](qint64 frame) {
    QImage image(4, 3, QImage::Format_RGB888);
    image.fill(QColor(int(frame % 256), 100, 50));
    return image;
  };
  for (qint64 frame = 100; frame < 130; ++frame) {
    overlay->showWatchedFrame(3, picture(frame), frame);
    if (frame % 8 == 0) overlay->showFrame(3, picture(frame), frame);  // the same frame again
  }
  for (qint64 pose_frame : {117, 104, 129}) {
    lumistage::PipelineSnapshot snapshot;
    snapshot.pose_frame = pose_frame;
    overlay->showSnapshot(snapshot);
    QCOMPARE(overlay->view()->image().pixelColor(0, 0).red(), int(pose_frame));
  }
}
