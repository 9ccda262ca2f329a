// The main window's viewport: orbited by the mouse, snapped to a camera, played along a path,
// and the clones placed in it.
#include <QListWidget>
#include <QPushButton>
#include <QSignalSpy>
#include <QSlider>
#include <QThread>
#include <QtTest>

#include "tests/ui/main_window_test.h"
#include "ui/clone_panel.h"
#include "ui/main_window.h"
#include "ui/viewport_panel.h"

using lumistage::MainWindow;

void MainWindowTest::viewportDragOrbitsToTheActorsBack() {
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

void MainWindowTest::viewportSnapsToACameraAndPlaysAPath() {
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

void MainWindowTest::clonesAreAddedDraggedTurnedAndRemoved() {
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
