// The studio's main window under Qt's offscreen platform: its rig, sources and settings; and
// the helpers the tests of its panels share (main_window_test.h).
#include "ui/main_window.h"

#include <QComboBox>
#include <QElapsedTimer>
#include <QFile>
#include <QFileInfo>
#include <QImage>
#include <QMenu>
#include <QMessageBox>
#include <QMouseEvent>
#include <QSettings>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QTimer>
#include <QToolButton>
#include <QtTest>

#include "core/body/human_model.h"
#include "core/body/mesh_io.h"
#include "core/capture/session_writer.h"
#include "core/geometry/ring_rig.h"
#include "core/render/view_recorder.h"
#include "core/sim/virtual_studio.h"
#include "tests/ui/main_window_test.h"
#include "ui/health_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/viewport_panel.h"

using lumistage::MainWindow;

// Pixels of a node's colour in the stage plan: cameras and their fields of view.
int MainWindowTest::pixelsNear(const QImage& image, const QColor& colour) {
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
void MainWindowTest::writeSession(const QString& folder, int cameras, int cameras_per_node,
                                  double fps, int frames) {
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
void MainWindowTest::writeStudioSession(const QString& folder, int frames) {
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

// A left drag over the viewport (QTest's mouseMove carries no buttons in Qt 6: send events).
void MainWindowTest::drag(QWidget* widget, QPoint from, QPoint to, Qt::MouseButton button,
                          Qt::KeyboardModifiers modifiers) {
  QMouseEvent press(QEvent::MouseButtonPress, from, widget->mapToGlobal(from), button, button,
                    modifiers);
  QApplication::sendEvent(widget, &press);
  for (int k = 1; k <= 4; ++k) {
    const QPoint p = from + (to - from) * k / 4;
    QMouseEvent move(QEvent::MouseMove, p, widget->mapToGlobal(p), Qt::NoButton, button, modifiers);
    QApplication::sendEvent(widget, &move);
  }
  QMouseEvent release(QEvent::MouseButtonRelease, to, widget->mapToGlobal(to), button, Qt::NoButton,
                      modifiers);
  QApplication::sendEvent(widget, &release);
}

// Answers the next message box that shows (within 10 s) with `button`; its text goes to *asked.
void MainWindowTest::answerNextMessageBox(QMessageBox::StandardButton button, QString* asked) {
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
void MainWindowTest::writeLeftOpenRecording(const QString& partial, int frames) {
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

void MainWindowTest::opensTheReferenceRig() {
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

void MainWindowTest::unknownSourceIsRefusedWithTheChoices() {
  lumistage::SourceSpec spec;
  QVERIFY(lumistage::SourceSpec::parse("webcam", spec)
              .contains("expected virtual[:CONFIG], session:DIR"));
}

void MainWindowTest::badRigKeepsThePreviousOneAndSaysWhy() {
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

// A laptop's 1366x768 screen (less its panel and the title bar) holds the whole default window
// with the reference rig's 12 cameras: it used to need 1555 x 874 pixels at least (the viewport's
// six layer check boxes, 160x120 camera tiles, a fixed 240x180 preview).
void MainWindowTest::theWindowFitsALaptopScreen() {
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

// The generic human chosen beside the source is remembered between runs, and a pipeline runs
// on the one chosen when it started (the choice is closed meanwhile).
void MainWindowTest::bodyChoiceIsRememberedAndHeldWhileThePipelineRuns() {
  const auto choice = [](MainWindow& w) {
    return w.pipeline()->findChild<QComboBox*>("pipeline_body");
  };
  {
    MainWindow window;
    QCOMPARE(window.pipeline()->body().detail, lumistage::BodyDetail::kStandard);
    QCOMPARE(choice(window)->currentText(), QString("Standard body"));
    choice(window)->setCurrentIndex(choice(window)->findText("Fine body"));
    QCOMPARE(window.pipeline()->body().detail, lumistage::BodyDetail::kFine);
  }
  QTemporaryDir dir;
  writeStudioSession(dir.filePath("session"), 4);
  MainWindow window;
  QCOMPARE(window.pipeline()->body().detail, lumistage::BodyDetail::kFine);
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
  window.pipeline()->setBody(lumistage::BodyChoice{});
  QCOMPARE(QSettings("Lumistage", "Studio").value("pipeline/body").toString(), QString("standard"));
}

// A rigged human of the user's own is chosen from a file: read in a child process (a file that
// crashes the mesh library costs the child, not the studio), refused saying why, remembered.
void MainWindowTest::aBodyFileIsReadApartAndRefusedSayingWhy() {
  QTemporaryDir dir;
  lumistage::HumanModelSpec spec;
  spec.target_vertices = 500;
  const QString good = dir.filePath("actor.glb");
  lumistage::saveSkinnedMeshGltf(lumistage::makeHumanModel(spec), good.toStdString());
  const QString garbage = dir.filePath("broken.fbx");
  {
    QFile file(garbage);
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write("garbage\n");
  }
  // Assimp's COLLADA parser recurses per nested node: this one overflows its stack.
  const QString deep = dir.filePath("deep.dae");
  {
    QFile file(deep);
    QVERIFY(file.open(QIODevice::WriteOnly));
    QByteArray text =
        "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/"
        "COLLADASchema\" version=\"1.4.1\">\n<library_visual_scenes><visual_scene id=\"s\">";
    for (int i = 0; i < 100000; ++i) text += "<node id=\"n\">";
    for (int i = 0; i < 100000; ++i) text += "</node>";
    text +=
        "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/>"
        "</scene></COLLADA>\n";
    file.write(text);
  }
  const auto choice = [](MainWindow& w) {
    return w.pipeline()->findChild<QComboBox*>("pipeline_body");
  };
  {
    MainWindow window;
    const lumistage::Status chosen = window.pipeline()->chooseBodyFile(good);
    QVERIFY2(chosen.ok(), chosen.error().c_str());
    QCOMPARE(QString::fromStdString(window.pipeline()->body().file.string()), good);
    QCOMPARE(choice(window)->currentText(), QString("actor.glb"));
    const lumistage::Status refused = window.pipeline()->chooseBodyFile(garbage);
    QVERIFY(!refused.ok());
    QVERIFY2(QString::fromStdString(refused.error()).contains(garbage), refused.error().c_str());
    const lumistage::Status crashed = window.pipeline()->chooseBodyFile(deep);
    QVERIFY(!crashed.ok());
    QVERIFY2(QString::fromStdString(crashed.error())
                 .contains(deep + ": the import crashed inside the mesh library ("),
             crashed.error().c_str());
    // Neither was taken: the good file stays chosen.
    QCOMPARE(QString::fromStdString(window.pipeline()->body().file.string()), good);
    QCOMPARE(choice(window)->findData(garbage), -1);
  }
  MainWindow window;  // remembered
  QCOMPARE(QString::fromStdString(window.pipeline()->body().file.string()), good);
  QCOMPARE(choice(window)->itemText(choice(window)->count() - 1), QString("Body file..."));
  window.pipeline()->setBody(lumistage::BodyChoice{});
  QCOMPARE(QSettings("Lumistage", "Studio").value("pipeline/body").toString(), QString("standard"));
}

void MainWindowTest::layoutIsRememberedBetweenRuns() {
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

QTEST_MAIN(MainWindowTest)
