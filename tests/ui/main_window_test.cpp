// The studio's main window under Qt's offscreen platform.
#include "ui/main_window.h"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <QCheckBox>
#include <QComboBox>
#include <QDir>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QFile>
#include <QFileInfo>
#include <QHeaderView>
#include <QImage>
#include <QLabel>
#include <QLineEdit>
#include <QListWidget>
#include <QMenu>
#include <QMessageBox>
#include <QMouseEvent>
#include <QProcess>
#include <QPushButton>
#include <QRegularExpression>
#include <QSettings>
#include <QSignalSpy>
#include <QSlider>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QThread>
#include <QTimer>
#include <QToolButton>
#include <QtTest>
#include <atomic>

#include "core/body/human_model.h"
#include "core/calib/calibration_report.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_writer.h"
#include "core/geometry/epipolar.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/ring_rig.h"
#include "core/render/view_recorder.h"
#include "core/sim/virtual_studio.h"
#include "tests/feed_receiver.h"
#include "tests/osc_receiver.h"
#include "ui/calibration_panel.h"
#include "ui/camera_grid_panel.h"
#include "ui/camera_overlay_view.h"
#include "ui/clone_panel.h"
#include "ui/health_panel.h"
#include "ui/live_table.h"
#include "ui/overlay_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/stage_plan_view.h"
#include "ui/viewport_panel.h"

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
      // An empty green screen (RGGB), a little brighter each frame.
      for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x)
          image.pixels[y * 64 + x] = uint8_t((x + y) % 2 == 1 ? 150 + 10 * f : 30 + 5 * f);
      writer.writeFrame(f, static_cast<int64_t>(f * 1e9 / fps),
                        std::vector<lumistage::ImageView>(cameras, image.view()));
    }
  }

  // A small session of the virtual studio (an actor on stage, so that the pipeline renders it):
  // a ring of 4 cameras of 320x240 on 2 nodes.
  static void writeStudioSession(const QString& folder, int frames) {
    lumistage::StudioConfig config;
    lumistage::RingRigSpec spec;
    spec.cameras = 4;
    spec.cameras_per_node = 2;
    spec.width = 320;
    spec.height = 240;
    config.rig = lumistage::makeRingRig(spec);
    config.actor.target_vertices = 2000;
    lumistage::VirtualStudio studio(config, frames);
    lumistage::SessionWriter writer(folder.toStdString(), config.rig, lumistage::PixelFormat::kRgb8,
                                    config.fps, "test");
    lumistage::StudioFrame frame;
    std::vector<lumistage::Image> images(spec.cameras);
    for (int f = 0; f < frames; ++f) {
      studio.renderFrame(f, frame);
      std::vector<lumistage::ImageView> views;
      for (int c = 0; c < spec.cameras; ++c) {
        lumistage::rgbaToImage(frame.images[c].data(), spec.width, spec.height,
                               lumistage::PixelFormat::kRgb8, images[c]);
        views.push_back(images[c].view());
      }
      writer.writeFrame(f, static_cast<int64_t>(f * 1e9 / config.fps), views);
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

  // A live table (camera health, the pipeline's nodes) tells its view of a cell only when the
  // cell's text changed, and its columns fit their contents after each update, growing and
  // shrinking as ResizeToContents would, the stretched column left to fill the rest.
  void liveTablesRewriteOnlyWhatChangedAndFitTheirColumns() {
    QTableWidget table(2, 3);
    lumistage::makeLiveTable(table, 2);
    table.resize(600, 200);
    table.show();
    int changes = 0;
    connect(table.model(), &QAbstractItemModel::dataChanged, &table, [&] { ++changes; });
    lumistage::setLiveCell(table, 0, 0, "1");
    lumistage::setLiveCell(table, 1, 0, "2", Qt::red);
    lumistage::fitLiveColumns(table);
    const int narrow = table.columnWidth(0);
    changes = 0;
    lumistage::setLiveCell(table, 0, 0, "1");
    lumistage::setLiveCell(table, 1, 0, "2", Qt::red);
    QCOMPARE(changes, 0);  // the same text and colour: nothing for the view to redo
    lumistage::setLiveCell(table, 0, 0, "a much wider cell than before");
    QCOMPARE(changes, 1);
    lumistage::setLiveCell(table, 1, 0, "2", Qt::blue);
    QCOMPARE(changes, 2);
    QCOMPARE(table.item(1, 0)->foreground().color(), QColor(Qt::blue));
    lumistage::fitLiveColumns(table);
    const int wide = table.columnWidth(0);
    QVERIFY2(wide > narrow + 50, qPrintable(QString("%1 against %2").arg(wide).arg(narrow)));
    lumistage::setLiveCell(table, 0, 0, "1");
    lumistage::fitLiveColumns(table);
    QCOMPARE(table.columnWidth(0), narrow);
    QCOMPARE(table.horizontalHeader()->sectionResizeMode(2), QHeaderView::Stretch);
  }

  // The pipeline's figures say how long the studio waits for a late node, and only while it
  // does: the deadlines stretched to its answers are the latency a technician sees grow.
  void thePipelinesFiguresSayWhenTheStudioWaitsForALateNode() {
    lumistage::RunReport r;
    r.fps = r.fps_recent = 9.5;
    r.frames = 120;
    r.statistics_deadline_ms = r.image_deadline_ms = 120;
    const QString plain = lumistage::pipelineSummary(r);
    QVERIFY2(plain.contains("9.5 fps") && plain.contains("120 frames"), qPrintable(plain));
    QVERIFY2(!plain.contains("late node"), qPrintable(plain));
    r.deadlines_following = true;
    r.statistics_deadline_ms = 199.4;
    r.image_deadline_ms = 127;
    const QString waiting = lumistage::pipelineSummary(r);
    QVERIFY2(waiting.startsWith(plain) &&
                 waiting.contains("waiting for a late node: its statistics up to 199 ms, its "
                                  "images up to 127 ms"),
             qPrintable(waiting));
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

  // The green floor is the rig's stage box: the floor its cameras cover, or the rig file's box.
  void stagePlanDrawsTheRigsStage() {
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
    // Frames stop: late after half a second, lost after one, as the camera health panel says.
    window.stopSource();
    QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("late"), 1500);
    QTRY_COMPARE_WITH_TIMEOUT(grid->state(1), QString("lost"), 1200);
  }

  void pipelinePanelRunsNodesAndShowsTheirHealth() {
    QTemporaryDir dir;
    writeStudioSession(dir.filePath("session"), 6);
    MainWindow window;
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    options.takes = dir.filePath("takes").toStdString();
    window.pipeline()->start(options);
    QVERIFY(window.pipeline()->running());
    // Started as --pipeline SESSION starts it: the source box names a recorded session, not the
    // demo's.
    QCOMPARE(window.pipeline()->findChild<QComboBox*>("pipeline_source")->currentIndex(), 1);
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= 10, 20000);
    const lumistage::RunReport report = window.pipeline()->lastReport();
    QCOMPARE(static_cast<int>(report.nodes.size()), 2);
    for (const auto& node : report.nodes) QVERIFY2(!node.lost, node.name.c_str());
    QCOMPARE(window.pipeline()->table()->rowCount(), 4);  // a row per camera
    QCOMPARE(window.pipeline()->table()->item(0, 1)->text(), QString("streaming"));
    // The stages' times, named in words; the tooltip says what each covers and its report key.
    QTableWidget* stages = window.pipeline()->stageTable();
    QStringList names;
    for (int r = 0; r < stages->rowCount(); ++r) names << stages->item(r, 0)->text();
    QVERIFY2(names.contains("motion capture") && names.contains("visibility"),
             qPrintable(names.join(", ")));
    const int mocap = int(names.indexOf("motion capture"));
    QVERIFY(stages->item(mocap, 0)->toolTip().contains("(mocap)"));
    QVERIFY(stages->item(mocap, 1)->text().toDouble() > 0);

    // A take, from the panel's button: every node records its cameras into takes/take-001/<node>.
    auto* take_button = window.pipeline()->findChild<QPushButton*>("record_take");
    auto* take_name = window.pipeline()->findChild<QLineEdit*>("take_name");
    auto* take_status = window.pipeline()->findChild<QLabel*>("take_status");
    QVERIFY(take_button && take_name && take_status);
    QVERIFY(take_button->isEnabled());
    QCOMPARE(take_name->text(), QString("take-001"));
    // Before any take: each node's disk, its free space and how long that lasts at its cameras'
    // rate (the two nodes share this machine's disk), in the Take column and under the buttons.
    QTRY_VERIFY_WITH_TIMEOUT(
        window.pipeline()->table()->item(0, 6)->text().contains(" free (") &&
            window.pipeline()->table()->item(0, 6)->text().contains(" of takes)"),
        5000);
    QVERIFY2(take_status->text().contains("holds") && take_status->text().contains("of takes"),
             qPrintable(take_status->text()));
    // A name that is not a folder name is refused at once, and says why.
    take_name->setText("take one");
    take_button->click();
    QVERIFY2(take_status->text().contains("Cannot record the take: take name 'take one' has a "
                                          "character other than"),
             qPrintable(take_status->text()));
    QTest::qWait(500);  // snapshots come and go; the refusal stays, no take starts
    QVERIFY(!window.pipeline()->lastSnapshot().take_recording);
    QVERIFY2(take_status->text().contains("Cannot record the take"),
             qPrintable(take_status->text()));
    take_name->setText("take-001");
    take_button->click();
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastSnapshot().take_recording, 5000);
    QTRY_COMPARE_WITH_TIMEOUT(take_button->text(), QString("Stop take"), 2000);
    QVERIFY2(take_status->text().contains("Recording take take-001"),
             qPrintable(take_status->text()));
    auto written = [&] {
      int64_t least = std::numeric_limits<int64_t>::max();
      for (const auto& node : window.pipeline()->lastReport().nodes)
        least = std::min(least, node.take.take == "take-001" ? node.take.written : 0);
      return least;
    };
    QTRY_VERIFY_WITH_TIMEOUT(written() >= 3, 20000);
    QVERIFY2(window.pipeline()->table()->item(0, 6)->text().contains("sets"),
             qPrintable(window.pipeline()->table()->item(0, 6)->text()));
    take_button->click();
    QTRY_VERIFY_WITH_TIMEOUT(!window.pipeline()->lastSnapshot().take_recording, 5000);
    QTRY_VERIFY_WITH_TIMEOUT(
        [&] {
          for (const auto& node : window.pipeline()->lastReport().nodes)
            if (!node.take.finished) return false;
          return true;
        }(),
        20000);
    QCOMPARE(take_name->text(), QString("take-002"));  // the next take's name, offered
    for (const auto& node : window.pipeline()->lastReport().nodes) {
      const lumistage::SessionReader part(
          (dir.filePath("takes/take-001/") + QString::fromStdString(node.name)).toStdString());
      QCOMPARE(int64_t(part.frameCount()), node.take.written);
      QVERIFY(part.frameCount() >= 3);
    }

    // The director's view to a file and to a recording, from the viewport's controls.
    lumistage::ViewportPanel* viewport = window.viewport();
    QTRY_VERIFY_WITH_TIMEOUT(!viewport->viewport()->snapshot().view.isNull(), 5000);
    // The viewport shows the frames as the studio blends them, not the snapshots' five a second
    // (the report's count comes with the snapshots: a few frames late at either end).
    const int64_t views_before = viewport->viewport()->viewsShown();
    const int64_t blended_before = window.pipeline()->lastReport().frames;
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= blended_before + 40, 20000);
    const int64_t views = viewport->viewport()->viewsShown() - views_before;
    const int64_t blended = window.pipeline()->lastReport().frames - blended_before;
    qInfo("viewport: %lld views shown of %lld frames blended", static_cast<long long>(views),
          static_cast<long long>(blended));
    QVERIFY2(views * 10 >= blended * 7,
             qPrintable(QString("%1 views shown of %2 frames blended").arg(views).arg(blended)));
    // The view's size, as chosen beside it: the nodes render at it from the next frames.
    QComboBox* size = viewport->sizeChoice();
    for (const int width : {960, 320}) {
      size->setCurrentIndex(size->findData(width));
      QTRY_COMPARE_WITH_TIMEOUT(viewport->viewport()->snapshot().view.width(), width, 5000);
      QCOMPARE(viewport->viewport()->snapshot().view.height(),
               viewport->viewport()->renderSize().height());
    }
    QString error;
    QVERIFY2(viewport->saveImage(dir.filePath("view.png"), &error), qPrintable(error));
    const QImage saved(dir.filePath("view.png"));
    QCOMPARE(saved.size(), viewport->viewport()->snapshot().view.size());
    QVERIFY(!viewport->saveImage(dir.filePath("missing/view.png"), &error));
    QVERIFY2(error.contains("missing/view.png"), qPrintable(error));
    viewport->record(true, dir.filePath("view.avi"));
    QTRY_VERIFY_WITH_TIMEOUT(viewport->viewport()->snapshot().recorded_frames >= 5, 10000);
    QCOMPARE(viewport->viewport()->snapshot().recording, dir.filePath("view.avi"));
    viewport->record(false);
    QTRY_VERIFY_WITH_TIMEOUT(viewport->viewport()->snapshot().recording.isEmpty(), 5000);
    QFile video(dir.filePath("view.avi"));
    QVERIFY(video.open(QIODevice::ReadOnly));
    const QByteArray head = video.read(12);
    QCOMPARE(head.left(4), QByteArray("RIFF"));
    QCOMPARE(head.mid(8, 4), QByteArray("AVI "));
    QVERIFY(!viewport->recording());
    // A recording that cannot be written (a folder has its name) ends; the pipeline goes on.
    QVERIFY(QDir(dir.path()).mkdir("taken.avi"));
    viewport->record(true, dir.filePath("taken.avi"));
    QVERIFY(viewport->recording());
    QTRY_VERIFY_WITH_TIMEOUT(!viewport->recording(), 5000);
    const int64_t frames = window.pipeline()->lastReport().frames;
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames > frames + 3, 5000);
    // Why, still said under the figures the frames since have rewritten.
    const QString summary = window.pipeline()->findChild<QLabel*>("pipeline_summary")->text();
    QVERIFY2(summary.contains("fps") && summary.contains("taken.avi"), qPrintable(summary));
    // A partial file of the name, left by a recording that never closed: kept, the recording goes
    // beside it, and the studio offers to recover it (not now). The settings name the recording
    // under way until it ends, for a studio started after this one died.
    writeLeftOpenRecording(dir.filePath("last.partial.avi"), 4);
    QString offered;
    answerNextMessageBox(QMessageBox::No, &offered);
    // Stopping the pipeline ends a recording: the file is finished, the button goes up.
    viewport->record(true, dir.filePath("last.avi"));
    QTRY_VERIFY_WITH_TIMEOUT(viewport->viewport()->snapshot().recorded_frames >= 2, 10000);
    QTRY_VERIFY_WITH_TIMEOUT(!offered.isEmpty(), 10000);
    QVERIFY2(offered.contains("under this name never closed") &&
                 offered.contains(dir.filePath("last.partial.avi")) &&
                 offered.contains(dir.filePath("last-recovered.avi")),
             qPrintable(offered));
    QCOMPARE(QSettings("Lumistage", "Studio").value("recording/open").toString(),
             dir.filePath("last.partial-2.avi"));

    QVERIFY(!viewport->viewport()->snapshot().view.isNull());
    window.pipeline()->stop();
    QVERIFY(!window.pipeline()->running());
    QVERIFY(!viewport->recording());
    QVERIFY(QFileInfo(dir.filePath("last.avi")).size() > 1000);
    QVERIFY(QFile::exists(dir.filePath("last.partial.avi")));
    QVERIFY(!QFile::exists(dir.filePath("last-recovered.avi")));
    QVERIFY(!QSettings("Lumistage", "Studio").contains("recording/open"));
    // The panel says how the recording ended, and no node is shown streaming any more.
    auto* summary_label = window.pipeline()->findChild<QLabel*>("pipeline_summary");
    QTRY_VERIFY_WITH_TIMEOUT(
        summary_label->text().contains("Recorded") && summary_label->text().contains("last.avi"),
        2000);
    QCOMPARE(window.pipeline()->findChild<QTableWidget*>("pipeline_nodes")->rowCount(), 0);
    // The viewport forgets the stopped pipeline's last image and body.
    QVERIFY(viewport->viewport()->snapshot().view.isNull());
    QVERIFY(!viewport->viewport()->snapshot().mesh);
    // Nothing to record without the pipeline: the button goes back up.
    viewport->record(true, dir.filePath("again.avi"));
    QVERIFY(!viewport->recording());
    QVERIFY(!QFile::exists(dir.filePath("again.avi")));
  }

  // A pipeline or a source that cannot start (a folder that is no session) ends by itself: it
  // says why, and the studio is ready to start again, its controls pointing at no worker that
  // is gone (they crashed the studio before).
  void aPipelineOrSourceThatCannotStartSaysWhyAndCanStartAgain() {
    QTemporaryDir dir;
    MainWindow window;
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("nothing").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    QTRY_VERIFY_WITH_TIMEOUT(!window.pipeline()->running(), 10000);
    auto* summary = window.pipeline()->findChild<QLabel*>("pipeline_summary");
    QVERIFY2(summary->text().contains("nothing"), qPrintable(summary->text()));
    window.pipeline()->setView(window.viewport()->viewport()->viewData());
    window.pipeline()->killNode("node1");
    window.pipeline()->stopRecording();
    QVERIFY(!window.pipeline()->startRecording(dir.filePath("v.avi")));
    window.pipeline()->stop();

    lumistage::SourceSpec spec;
    QVERIFY(lumistage::SourceSpec::parse("session:" + dir.filePath("nothing"), spec).isEmpty());
    QSignalSpy failed(&window, &MainWindow::sourceFailed);
    window.startSource(spec);
    QTRY_VERIFY_WITH_TIMEOUT(!window.sourceRunning(), 10000);
    QCOMPARE(failed.count(), 1);
    window.stopSource();
    QVERIFY(lumistage::SourceSpec::parse("virtual", spec).isEmpty());
    window.startSource(spec);
    QVERIFY(window.sourceRunning());
    window.stopSource();
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

  // A left drag over the viewport (QTest's mouseMove carries no buttons in Qt 6: send events).
  static void drag(QWidget* widget, QPoint from, QPoint to, Qt::MouseButton button,
                   Qt::KeyboardModifiers modifiers = Qt::NoModifier) {
    QMouseEvent press(QEvent::MouseButtonPress, from, widget->mapToGlobal(from), button, button,
                      modifiers);
    QApplication::sendEvent(widget, &press);
    for (int k = 1; k <= 4; ++k) {
      const QPoint p = from + (to - from) * k / 4;
      QMouseEvent move(QEvent::MouseMove, p, widget->mapToGlobal(p), Qt::NoButton, button,
                       modifiers);
      QApplication::sendEvent(widget, &move);
    }
    QMouseEvent release(QEvent::MouseButtonRelease, to, widget->mapToGlobal(to), button,
                        Qt::NoButton, modifiers);
    QApplication::sendEvent(widget, &release);
  }

  void viewportDragOrbitsToTheActorsBack() {
    MainWindow window;
    window.resize(1200, 900);
    window.show();
    QCOMPARE(window.openRig(reference_), QString());
    lumistage::ViewportWidget* viewport = window.viewport()->viewport();
    QSignalSpy sent(window.viewport(), &lumistage::ViewportPanel::viewChanged);
    const Eigen::Vector3d before = viewport->view().eye();
    // A drag across the viewport's full height turns the view half way round the target.
    const int h = viewport->height();
    drag(viewport, QPoint(10, h / 2), QPoint(10 + h, h / 2), Qt::LeftButton);
    const Eigen::Vector3d after = viewport->view().eye();
    const Eigen::Vector3d target = viewport->view().target();
    QVERIFY((before - target).head<2>().dot((after - target).head<2>()) < 0);  // other side
    QVERIFY(sent.count() >= 4);  // every move sends the view on for the nodes to render
    const lumistage::ViewData last = sent.last().at(0).value<lumistage::ViewData>();
    QCOMPARE(last.width, viewport->renderWidth());  // the size chosen beside the view
    QVERIFY(last.rotation.size() == 9);
    // Right drag pans, the wheel zooms.
    const Eigen::Vector3d target_before = viewport->view().target();
    drag(viewport, QPoint(100, 100), QPoint(160, 100), Qt::RightButton);
    QVERIFY((viewport->view().target() - target_before).norm() > 0.1);
    const double distance = viewport->view().distance();
    QWheelEvent wheel(QPointF(50, 50), viewport->mapToGlobal(QPointF(50, 50)), QPoint(),
                      QPoint(0, 120), Qt::NoButton, Qt::NoModifier, Qt::NoScrollPhase, false);
    QApplication::sendEvent(viewport, &wheel);
    QVERIFY(viewport->view().distance() < distance);
  }

  // A laptop's 1366x768 screen (less its panel and the title bar) holds the whole default window
  // with the reference rig's 12 cameras: it used to need 1555 x 874 pixels at least (the viewport's
  // six layer check boxes, 160x120 camera tiles, a fixed 240x180 preview).
  void theWindowFitsALaptopScreen() {
    MainWindow window;
    QCOMPARE(window.openRig(reference_), QString());
    window.resetLayout();
    window.resize(1366, 680);
    window.show();
    const QSize least = window.minimumSizeHint();
    QVERIFY2(least.width() <= 1366 && least.height() <= 680,
             qPrintable(QString("%1x%2").arg(least.width()).arg(least.height())));
    QCOMPARE(window.size(), QSize(1366, 680));
    // The layers are in the viewport's Layers menu, every one of them.
    auto* layers = window.viewport()->findChild<QToolButton*>("layers");
    QVERIFY(layers && layers->menu());
    QCOMPARE(layers->menu()->actions().size(), 6);
  }

  void viewportSnapsToACameraAndPlaysAPath() {
    MainWindow window;
    QCOMPARE(window.openRig(reference_), QString());
    lumistage::ViewportPanel* panel = window.viewport();
    QVERIFY(panel->snapToCamera(3));
    QVERIFY((panel->viewport()->view().eye() - window.rig()->camera(3).centre()).norm() < 1e-6);
    QVERIFY(!panel->snapToCamera(99));
    auto* play = panel->findChild<QPushButton*>("play_path");
    QVERIFY(!play->isEnabled());  // no path to play yet: the button says so
    panel->setTime(0);
    panel->addKey();
    QVERIFY(!play->isEnabled());
    panel->setTime(1.0);  // moving along the timeline follows the path: snap after it
    QVERIFY(panel->snapToCamera(9));
    panel->addKey();
    QCOMPARE(panel->path().keys().size(), size_t(2));
    QVERIFY(play->isEnabled());
    panel->setTime(0);
    QVERIFY((panel->viewport()->view().eye() - window.rig()->camera(3).centre()).norm() < 1e-6);
    panel->play(true);
    QVERIFY(panel->playing());
    QTRY_VERIFY_WITH_TIMEOUT(!panel->playing(), 3000);  // stops at the last key
    QVERIFY((panel->viewport()->view().eye() - window.rig()->camera(9).centre()).norm() < 1e-6);
    // The path follows the clock, not the timer's ticks: a second of the path takes a second
    // even when ticks come late (here the event loop held up for 0.6 s: one tick).
    panel->setTime(0);
    panel->play(true);
    QThread::msleep(600);
    QCoreApplication::processEvents();
    QVERIFY2(panel->time() > 0.5, qPrintable(QString::number(panel->time())));
    panel->play(false);
    // A click in the timeline's groove (a page step), as a drag does, moves the time.
    auto* timeline = panel->findChild<QSlider*>("timeline");
    panel->setTime(0);
    timeline->triggerAction(QAbstractSlider::SliderPageStepAdd);
    QVERIFY(timeline->value() > 0);
    QCOMPARE(panel->time(), timeline->value() / 10.0);
    panel->setTime(1.0);
    QVERIFY(panel->removeKey());
    QCOMPARE(panel->path().keys().size(), size_t(1));
  }

  void calibrationCheckDrawsEpipolarLinesThroughTheSamePoint() {
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

  void calibrationReportGivesReprojectionErrors() {
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

  void clonesAreAddedDraggedTurnedAndRemoved() {
    MainWindow window;
    window.resize(1200, 900);
    window.show();
    QCOMPARE(window.openRig(reference_), QString());
    lumistage::ClonePanel* panel = window.clonePanel();
    const int a = panel->addClone();
    panel->addClone();
    QCOMPARE(panel->list()->count(), 2);
    QVERIFY(panel->turnSelected(0.5));
    // Shift+drag in the viewport moves the clone under the cursor along the floor.
    lumistage::ViewportWidget* viewport = window.viewport()->viewport();
    const lumistage::Camera view = viewport->view().camera(viewport->width(), viewport->height());
    const lumistage::Clone before = *window.clones().find(a);
    const auto at = view.project(before.transform() * Eigen::Vector3d::Zero());
    QVERIFY(at.has_value());
    const QPoint from(int(at->x()), int(at->y()));
    drag(viewport, from, from + QPoint(40, 0), Qt::LeftButton, Qt::ShiftModifier);
    QVERIFY((window.clones().find(a)->offset_m - before.offset_m).norm() > 0.05);
    QVERIFY(panel->list()->item(0)->text().contains("clone 1"));
    panel->list()->setCurrentRow(0);
    QVERIFY(panel->removeSelected());
    QCOMPARE(panel->list()->count(), 1);
    QVERIFY(window.clones().find(a) == nullptr);
  }

  void overlayShowsTheChosenCamera() {
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

  // The body placed for a frame is drawn over that frame's own picture: the chosen camera's every
  // frame reaches the overlay, a few a second (4) reach it for the others, and a frame that comes
  // by both ways is kept once.
  void overlayDrawsTheBodyOverThePictureOfItsFrame() {
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

  void theSourceSendsEveryFrameOfTheWatchedCamera() {
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

  // Answers the next message box that shows (within 10 s) with `button`; its text goes to *asked.
  static void answerNextMessageBox(QMessageBox::StandardButton button, QString* asked) {
    auto* timer = new QTimer;
    auto* clock = new QElapsedTimer;
    clock->start();
    QObject::connect(timer, &QTimer::timeout, [timer, clock, button, asked] {
      auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
      if (!box && clock->elapsed() < 10000) return;
      if (box) {
        *asked = box->text() + "\n" + box->informativeText();
        box->button(button)->click();
      }
      timer->stop();
      timer->deleteLater();
      delete clock;
    });
    timer->start(20);
  }

  // A recording of the view as a studio killed while recording leaves it (NAME.partial.avi: no
  // index, no counts in its headers): a closed one's, its index cut off and its sizes zeroed.
  static void writeLeftOpenRecording(const QString& partial, int frames) {
    const QString made = QFileInfo(partial).absolutePath() + "/made.avi";
    {
      lumistage::ViewRecorder recorder(made.toStdString(), 25);
      std::vector<uint8_t> rgba(size_t(64) * 48 * 4, 255);
      for (int f = 0; f < frames; ++f) {
        std::fill(rgba.begin(), rgba.end(), uint8_t(10 * f));
        QVERIFY(recorder.add(f, 64, 48, rgba));
      }
      QVERIFY(recorder.close());
    }
    QFile in(made);
    QVERIFY(in.open(QIODevice::ReadOnly));
    QByteArray d = in.readAll();
    in.close();
    QVERIFY(QFile::remove(made));
    const qsizetype movi = d.indexOf("movi") - 8, index = d.lastIndexOf("idx1");
    QVERIFY(movi > 0 && index > movi);
    d.truncate(index);
    for (const qsizetype at : {qsizetype(4), movi + 4}) d.replace(at, 4, QByteArray(4, '\0'));
    QFile out(partial);
    QVERIFY(out.open(QIODevice::WriteOnly));
    QCOMPARE(out.write(d), d.size());
  }

  // The studio ended while recording the view (killed, crashed, power lost: its settings still
  // name the recording it had open). The next studio offers to recover it, once, and makes a
  // whole video of it beside it; one that a studio still running records is left alone.
  void aRecordingLeftOpenIsOfferedForRecovery() {
    QTemporaryDir dir;
    const QString partial = dir.filePath("view.partial.avi");
    writeLeftOpenRecording(partial, 12);
    const auto leaveOpen = [&](qint64 pid) {
      QSettings settings("Lumistage", "Studio");
      settings.setValue("recording/open", partial);
      settings.setValue("recording/open_pid", pid);
    };
    QProcess running;  // the studio recording it, still running
    running.start("sleep", {"60"});
    QVERIFY(running.waitForStarted());
    leaveOpen(running.processId());
    {
      MainWindow window;
      window.show();
      QTest::qWait(300);
      QVERIFY(!QApplication::activeModalWidget());
    }
    QCOMPARE(QSettings("Lumistage", "Studio").value("recording/open").toString(), partial);
    running.kill();  // and now gone
    QVERIFY(running.waitForFinished());

    QString asked;
    answerNextMessageBox(QMessageBox::Yes, &asked);
    MainWindow window;
    QSignalSpy recovered(&window, &MainWindow::recordingRecovered);
    window.show();
    QTRY_COMPARE_WITH_TIMEOUT(recovered.count(), 1, 20000);
    const QString video = dir.filePath("view-recovered.avi");
    QVERIFY2(asked.contains("ended while it was recording the view") &&
                 asked.contains("into\n" + video + "?") && asked.contains(":\n" + partial),
             qPrintable(asked));
    QCOMPARE(recovered[0][0].toString(), video);
    QCOMPARE(recovered[0][1].toString(), QString());
    const QString status = window.findChild<QLabel*>("status")->text();
    QVERIFY2(status.contains("Recovered 12 frames (0.5 s) of the view into " + video),
             qPrintable(status));
    QVERIFY(QFileInfo(video).size() > QFileInfo(partial).size());  // its index written
    QVERIFY(QFile::exists(partial));
    QVERIFY(!QSettings("Lumistage", "Studio").contains("recording/open"));
    {
      MainWindow again;  // asked once
      again.show();
      QTest::qWait(300);
      QVERIFY(!QApplication::activeModalWidget());
    }
    // What is not such a recording says why.
    window.recoverRecording(video);
    QTRY_COMPARE_WITH_TIMEOUT(recovered.count(), 2, 20000);
    QCOMPARE(recovered[1][0].toString(), QString());
    QVERIFY2(recovered[1][1].toString().contains("it was closed"),
             qPrintable(recovered[1][1].toString()));
    QVERIFY(window.findChild<QLabel*>("status")->text().startsWith(
        "Cannot recover the recording: " + video));
  }

  // A take and the view being recorded: closing the window asks first. Cancel keeps both
  // recording; Close ends them, their files whole.
  void closingWhileRecordingAsksFirst() {
    QTemporaryDir dir;
    writeStudioSession(dir.filePath("session"), 6);
    MainWindow window;
    window.show();
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    options.takes = dir.filePath("takes").toStdString();
    window.pipeline()->start(options);
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= 5, 20000);
    QVERIFY(window.recordingsUnderWay().isEmpty());
    QVERIFY(window.pipeline()->startTake("take-001"));
    window.viewport()->record(true, dir.filePath("view.avi"));
    auto written = [&] {  // frame sets in the take, by the node that wrote the fewest
      int64_t least = std::numeric_limits<int64_t>::max();
      for (const auto& node : window.pipeline()->lastReport().nodes)
        least = std::min(least, node.take.take == "take-001" ? node.take.written : 0);
      return least;
    };
    QTRY_VERIFY_WITH_TIMEOUT(
        written() >= 2 && window.pipeline()->lastSnapshot().recorded_frames >= 2, 20000);
    QString asked;
    answerNextMessageBox(QMessageBox::Cancel, &asked);
    QVERIFY(!window.close());
    QVERIFY2(asked.contains("the take take-001") && asked.contains(dir.filePath("view.avi")),
             qPrintable(asked));
    QVERIFY(window.isVisible());
    QVERIFY(window.pipeline()->running());
    QVERIFY(window.viewport()->recording());
    const int64_t recorded = window.pipeline()->lastSnapshot().recorded_frames;
    const int64_t taken = written();
    QTRY_VERIFY_WITH_TIMEOUT(
        window.pipeline()->lastSnapshot().recorded_frames > recorded && written() > taken, 10000);
    QVERIFY(window.pipeline()->lastSnapshot().take_recording);

    asked.clear();
    answerNextMessageBox(QMessageBox::Close, &asked);
    QVERIFY(window.close());
    QVERIFY(!asked.isEmpty());
    QVERIFY(!window.isVisible());
    QVERIFY(!window.pipeline()->running());
    QVERIFY(QFileInfo(dir.filePath("view.avi")).size() > 1000);
    for (const char* node : {"node1", "node2"}) {
      const lumistage::SessionReader part((dir.filePath("takes/take-001/") + node).toStdString());
      QVERIFY2(part.frameCount() > taken, node);
    }
  }

  // The generic human chosen beside the source is remembered between runs, and a pipeline runs
  // on the one chosen when it started (the choice is closed meanwhile).
  void bodyChoiceIsRememberedAndHeldWhileThePipelineRuns() {
    const auto choice = [](MainWindow& w) {
      return w.pipeline()->findChild<QComboBox*>("pipeline_body");
    };
    {
      MainWindow window;
      QCOMPARE(window.pipeline()->body(), lumistage::BodyDetail::kStandard);
      QCOMPARE(choice(window)->currentText(), QString("Standard body"));
      choice(window)->setCurrentIndex(choice(window)->findText("Fine body"));
      QCOMPARE(window.pipeline()->body(), lumistage::BodyDetail::kFine);
    }
    QTemporaryDir dir;
    writeStudioSession(dir.filePath("session"), 4);
    MainWindow window;
    QCOMPARE(window.pipeline()->body(), lumistage::BodyDetail::kFine);
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    QVERIFY(!choice(window)->isEnabled());
    // The nodes pose the fine body as the studio does: its offsets are used, views come.
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= 3, 30000);
    QVERIFY(!window.pipeline()->lastSnapshot().view.isNull());
    QCOMPARE(window.pipeline()->lastSnapshot().mesh->positions.cols(),
             lumistage::loadGenericHuman(lumistage::BodyDetail::kFine).rest.vertexCount());
    window.pipeline()->stop();
    QVERIFY(choice(window)->isEnabled());
    window.pipeline()->setBody(lumistage::BodyDetail::kStandard);
    QCOMPARE(QSettings("Lumistage", "Studio").value("pipeline/body").toString(),
             QString("standard"));
  }

  void layoutIsRememberedBetweenRuns() {
    {
      MainWindow window;
      window.show();
      window.resetLayout();
      window.showPanel("health")->parentWidget()->hide();  // the health dock
      window.close();
    }
    {
      MainWindow window;
      window.show();
      QVERIFY(!window.health()->parentWidget()->isVisible());
      window.resetLayout();
      QVERIFY(window.health()->parentWidget()->isVisible());
      window.close();
    }
  }

  void healthShowsAKilledNodeLostWithinASecond() {
    // A technician's check: a node stops (its plug pulled); its cameras turn red, in words,
    // within a second, and the other node's stay green.
    QTemporaryDir dir;
    writeSession(dir.filePath("session"), 4, 2, 20.0, 4);
    MainWindow window;
    window.resize(1200, 900);
    window.show();
    QCOMPARE(window.openRig(dir.filePath("session") + "/rig.yaml"), QString());
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    lumistage::HealthPanel* health = window.health();
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames >= 10, 20000);
    int kept = -1, killed = -1, killed_too = -1;  // cameras of node1, two of node2
    for (int c = 0; c < window.rig()->cameraCount(); ++c) {
      const std::string node = window.rig()->camera(c).node();
      if (node == "node1") kept = c;
      if (node == "node2") (killed < 0 ? killed : killed_too) = c;
    }
    QVERIFY(kept >= 0 && killed >= 0 && killed_too >= 0);
    QTRY_COMPARE_WITH_TIMEOUT(health->verdict(kept).state, lumistage::HealthState::kStreaming,
                              3000);
    QTRY_COMPARE_WITH_TIMEOUT(health->verdict(killed).state, lumistage::HealthState::kStreaming,
                              3000);
    QVERIFY(!health->history().samples("cam01/fps").empty());
    // How long each camera's node takes to answer the studio, in milliseconds, and its history.
    QTableWidget* table = health->table();
    int answer = -1;
    for (int col = 0; col < table->columnCount(); ++col)
      if (table->horizontalHeaderItem(col)->text() == "Node ms") answer = col;
    QVERIFY(answer >= 0);
    QTRY_VERIFY_WITH_TIMEOUT(table->item(kept, answer)->text().toDouble() > 0, 3000);
    QVERIFY2(table->item(kept, answer)->text().toDouble() < 5000,
             qPrintable(table->item(kept, answer)->text()));
    const std::string kept_name = window.rig()->camera(kept).name();
    QVERIFY(!health->history().samples(kept_name + "/answer").empty());
    window.pipeline()->killNode("node2");
    QElapsedTimer clock;
    clock.start();
    QTRY_COMPARE_WITH_TIMEOUT(health->verdict(killed).state, lumistage::HealthState::kLost, 1000);
    QVERIFY(clock.elapsed() < 1000);
    QVERIFY2(QString::fromStdString(health->verdict(killed_too).words).contains("exited"),
             health->verdict(killed_too).words.c_str());
    QCOMPARE(table->item(killed, answer)->text(), QString("-"));  // a gone node answers nothing
    // The other node never goes lost; on a loaded machine it may be late for a moment.
    QVERIFY(health->verdict(kept).state != lumistage::HealthState::kLost);
    QTRY_COMPARE_WITH_TIMEOUT(health->verdict(kept).state, lumistage::HealthState::kStreaming,
                              3000);
    QTRY_COMPARE_WITH_TIMEOUT(health->table()->item(killed, 1)->text(), QString("lost"), 500);
    window.pipeline()->stop();
  }
  // The live skeleton: checked, every frame shown goes to its receiver as a VMC bundle (a liblo
  // server here, on 127.0.0.1), from the pipeline's first frame; unchecked, none; a receiver that
  // is not HOST:PORT is refused beside the box, which unchecks.
  void theLiveSkeletonBoxStreamsEveryFrameShownToItsReceiver() {
    QTemporaryDir dir;
    writeStudioSession(dir.filePath("session"), 6);
    lumistage::testing::OscReceiver receiver;
    QVERIFY(receiver.port() > 0);
    MainWindow window;
    auto* box = window.pipeline()->findChild<QCheckBox*>("live_skeleton");
    auto* target = window.pipeline()->findChild<QLineEdit*>("live_skeleton_target");
    auto* status = window.pipeline()->findChild<QLabel*>("live_skeleton_status");
    QVERIFY(box && target && status);
    target->setText("localhost");
    box->setChecked(true);
    QVERIFY(!box->isChecked());
    QVERIFY2(status->text().contains("expected HOST:PORT"), qPrintable(status->text()));
    QVERIFY2(status->toolTip().contains("no port"), qPrintable(status->toolTip()));
    target->setText(QString("127.0.0.1:%1").arg(receiver.port()));
    box->setChecked(true);
    QVERIFY(box->isChecked());
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    QTRY_VERIFY_WITH_TIMEOUT(receiver.bundles().size() >= 5, 30000);
    QCOMPARE(receiver.bundles().front().size(), size_t(25));
    QCOMPARE(receiver.bundles().front()[1].text(0), std::string("Hips"));
    QTRY_VERIFY_WITH_TIMEOUT(status->text().contains("frames sent"), 5000);
    // Unchecked: the stream stops, after the frames the panel says, every one received.
    box->setChecked(false);
    auto* summary = window.pipeline()->findChild<QLabel*>("pipeline_summary");
    const QRegularExpression stopped("Stopped the skeleton's stream to .* after (\\d+) frames");
    QTRY_VERIFY_WITH_TIMEOUT(stopped.match(summary->text()).hasMatch(), 5000);
    const size_t sent = stopped.match(summary->text()).captured(1).toULongLong();
    QTRY_COMPARE_WITH_TIMEOUT(receiver.bundles().size(), sent, 5000);
    const int64_t frames = window.pipeline()->lastReport().frames;
    QTRY_VERIFY_WITH_TIMEOUT(window.pipeline()->lastReport().frames > frames + 5, 20000);
    QCOMPARE(receiver.bundles().size(), sent);
    QCOMPARE(QSettings("Lumistage", "Studio").value("pipeline/osc").toString(), target->text());
    window.pipeline()->stop();
  }
  // The live view: checked, the director's view goes out as H.264 in MPEG-TS to its URL, here
  // udp:// to an FFmpeg receiver on 127.0.0.1 that decodes it; a URL that is not a feed's is
  // refused beside the box, which unchecks; unchecked, the feed stops and says what it sent.
  void theLiveViewBoxFeedsTheViewToAReceiver() {
    QTemporaryDir dir;
    writeStudioSession(dir.filePath("session"), 6);
    MainWindow window;
    auto* box = window.pipeline()->findChild<QCheckBox*>("live_feed");
    auto* url = window.pipeline()->findChild<QLineEdit*>("live_feed_url");
    auto* status = window.pipeline()->findChild<QLabel*>("live_feed_status");
    QVERIFY(box && url && status);
    url->setText("rtmp://127.0.0.1/live");
    box->setChecked(true);
    QVERIFY(!box->isChecked());
    QVERIFY2(status->text().contains("expected udp:// or srt://"), qPrintable(status->text()));
    QVERIFY2(status->toolTip().contains("not 'rtmp'"), qPrintable(status->toolTip()));
    const int port = [] {  // a port nobody holds now: the system's choice, released
      const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
      sockaddr_in address{};
      address.sin_family = AF_INET;
      address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      ::bind(s, reinterpret_cast<sockaddr*>(&address), sizeof address);
      socklen_t length = sizeof address;
      ::getsockname(s, reinterpret_cast<sockaddr*>(&address), &length);
      ::close(s);
      return int(ntohs(address.sin_port));
    }();
    const QString feed = QString("udp://127.0.0.1:%1").arg(port);
    lumistage::testing::FeedReceiver receiver(feed.toStdString(), 3, std::chrono::seconds(120));
    QVERIFY(lumistage::testing::waitForUdpPort(port, std::chrono::seconds(30)));
    url->setText(feed);
    box->setChecked(true);
    QVERIFY(box->isChecked());
    lumistage::LocalRunOptions options;
    options.session = dir.filePath("session").toStdString();
    options.node_binary = LUMISTAGE_NODE;
    window.pipeline()->start(options);
    QTRY_VERIFY_WITH_TIMEOUT(receiver.finished(), 120000);
    const std::vector<lumistage::testing::DecodedPicture> pictures = receiver.wait();
    QVERIFY2(pictures.size() == 3, receiver.error().c_str());
    // At the view's size when the feed started (the viewport may size the view since: scaled).
    for (const lumistage::testing::DecodedPicture& p : pictures) {
      QVERIFY(p.width >= 16 && p.height >= 16);
      QCOMPARE(p.width % 2, 0);
    }
    QTRY_VERIFY_WITH_TIMEOUT(status->text().contains(" sent, "), 5000);
    box->setChecked(false);
    auto* summary = window.pipeline()->findChild<QLabel*>("pipeline_summary");
    const QRegularExpression stopped("Stopped the view's feed to .* after (\\d+) frames");
    QTRY_VERIFY_WITH_TIMEOUT(stopped.match(summary->text()).hasMatch(), 5000);
    QVERIFY(stopped.match(summary->text()).captured(1).toLongLong() >= 3);
    QCOMPARE(QSettings("Lumistage", "Studio").value("pipeline/feed").toString(), feed);
    window.pipeline()->stop();
  }
};

QTEST_MAIN(MainWindowTest)
#include "main_window_test.moc"
