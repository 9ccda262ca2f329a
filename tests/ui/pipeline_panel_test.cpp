// The main window's pipeline panel and camera health: nodes started, watched and lost, the
// pipeline's figures, and the live skeleton sent out.
#include "ui/pipeline_panel.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDir>
#include <QElapsedTimer>
#include <QFile>
#include <QFileInfo>
#include <QHeaderView>
#include <QImage>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QPushButton>
#include <QRegularExpression>
#include <QSettings>
#include <QSignalSpy>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QtTest>

#include "core/capture/session_reader.h"
#include "tests/feed_receiver.h"
#include "tests/osc_receiver.h"
#include "tests/ui/main_window_test.h"
#include "ui/health_panel.h"
#include "ui/live_table.h"
#include "ui/main_window.h"
#include "ui/source_worker.h"
#include "ui/viewport_panel.h"

using lumistage::MainWindow;

// A live table (camera health, the pipeline's nodes) tells its view of a cell only when the
// cell's text changed, and its columns fit their contents after each update, growing and
// shrinking as ResizeToContents would, the stretched column left to fill the rest.
void MainWindowTest::liveTablesRewriteOnlyWhatChangedAndFitTheirColumns() {
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
void MainWindowTest::thePipelinesFiguresSayWhenTheStudioWaitsForALateNode() {
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

void MainWindowTest::pipelinePanelRunsNodesAndShowsTheirHealth() {
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
  QVERIFY2(take_status->text().contains("Cannot record the take"), qPrintable(take_status->text()));
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
void MainWindowTest::aPipelineOrSourceThatCannotStartSaysWhyAndCanStartAgain() {
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

void MainWindowTest::healthShowsAKilledNodeLostWithinASecond() {
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
  QTRY_COMPARE_WITH_TIMEOUT(health->verdict(kept).state, lumistage::HealthState::kStreaming, 3000);
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
  QTRY_COMPARE_WITH_TIMEOUT(health->verdict(kept).state, lumistage::HealthState::kStreaming, 3000);
  QTRY_COMPARE_WITH_TIMEOUT(health->table()->item(killed, 1)->text(), QString("lost"), 500);
  window.pipeline()->stop();
}

// The live skeleton: checked, every frame shown goes to its receiver as a VMC bundle (a liblo
// server here, on 127.0.0.1), from the pipeline's first frame; unchecked, none; a receiver that
// is not HOST:PORT is refused beside the box, which unchecks.
void MainWindowTest::theLiveSkeletonBoxStreamsEveryFrameShownToItsReceiver() {
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
void MainWindowTest::theLiveViewBoxFeedsTheViewToAReceiver() {
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
  QVERIFY2(status->text().contains("expected udp://, srt:// or v4l2://"), qPrintable(status->text()));
  QVERIFY2(status->toolTip().contains("not 'rtmp'"), qPrintable(status->toolTip()));
  const int port = lumistage::testing::freeUdpPort();
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
