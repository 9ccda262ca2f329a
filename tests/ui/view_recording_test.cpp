// Recording the director's view from the main window: a recording left open is offered for
// recovery, and closing the window while recording asks first.
#include <QFile>
#include <QFileInfo>
#include <QLabel>
#include <QMessageBox>
#include <QProcess>
#include <QSettings>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QtTest>

#include "core/capture/session_reader.h"
#include "tests/ui/main_window_test.h"
#include "ui/main_window.h"
#include "ui/pipeline_panel.h"
#include "ui/viewport_panel.h"

using lumistage::MainWindow;

// The studio ended while recording the view (killed, crashed, power lost: its settings still
// name the recording it had open). The next studio offers to recover it, once, and makes a
// whole video of it beside it; one that a studio still running records is left alone.
void MainWindowTest::aRecordingLeftOpenIsOfferedForRecovery() {
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
  QVERIFY(window.findChild<QLabel*>("status")->text().startsWith("Cannot recover the recording: " +
                                                                 video));
}

// A take and the view being recorded: closing the window asks first. Cancel keeps both
// recording; Close ends them, their files whole.
void MainWindowTest::closingWhileRecordingAsksFirst() {
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
  QTRY_VERIFY_WITH_TIMEOUT(written() >= 2 && window.pipeline()->lastSnapshot().recorded_frames >= 2,
                           20000);
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
