#pragma once

// The studio's main window under Qt's offscreen platform: the one test class, its slots defined
// in the file named after what they test (main_window_test.cpp, camera_views_test.cpp,
// pipeline_panel_test.cpp, viewport_test.cpp, calibration_panel_test.cpp,
// view_recording_test.cpp), run in the order declared here.
#include <QColor>
#include <QImage>
#include <QMessageBox>
#include <QObject>
#include <QPoint>
#include <QString>
#include <QWidget>

class MainWindowTest : public QObject {
  Q_OBJECT

 private:
  const QString reference_ = QString(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml";

  // Pixels of a node's colour in the stage plan: cameras and their fields of view.
  static int pixelsNear(const QImage& image, const QColor& colour);

  // A small Bayer session of a ring of 64x48 cameras; frame f is flat grey 40 f.
  static void writeSession(const QString& folder, int cameras, int cameras_per_node, double fps,
                           int frames);

  // A small session of the virtual studio (an actor on stage, so that the pipeline renders it):
  // a ring of 4 cameras of 320x240 on 2 nodes.
  static void writeStudioSession(const QString& folder, int frames);

  // A left drag over the viewport (QTest's mouseMove carries no buttons in Qt 6: send events).
  static void drag(QWidget* widget, QPoint from, QPoint to, Qt::MouseButton button,
                   Qt::KeyboardModifiers modifiers = Qt::NoModifier);

  // Answers the next message box that shows (within 10 s) with `button`; its text goes to *asked.
  static void answerNextMessageBox(QMessageBox::StandardButton button, QString* asked);

  // A recording of the view as a studio killed while recording leaves it (NAME.partial.avi: no
  // index, no counts in its headers): a closed one's, its index cut off and its sizes zeroed.
  static void writeLeftOpenRecording(const QString& partial, int frames);

 private slots:
  void opensTheReferenceRig();
  void liveTablesRewriteOnlyWhatChangedAndFitTheirColumns();
  void thePipelinesFiguresSayWhenTheStudioWaitsForALateNode();
  void stagePlanDrawsEveryNode();
  void stagePlanDrawsTheRigsStage();
  void selectingACameraHighlightsIt();
  void previewsDecimateBayerIntoColour();
  void liveSessionShowsEveryCameraAndNoticesWhenFramesStop();
  void pipelinePanelRunsNodesAndShowsTheirHealth();
  void aPipelineOrSourceThatCannotStartSaysWhyAndCanStartAgain();
  void unknownSourceIsRefusedWithTheChoices();
  void badRigKeepsThePreviousOneAndSaysWhy();
  void viewportDragOrbitsToTheActorsBack();
  void theWindowFitsALaptopScreen();
  void viewportSnapsToACameraAndPlaysAPath();
  void calibrationCheckDrawsEpipolarLinesThroughTheSamePoint();
  void calibrationReportGivesReprojectionErrors();
  void clonesAreAddedDraggedTurnedAndRemoved();
  void overlayShowsTheChosenCamera();
  void overlayDrawsTheBodyOverThePictureOfItsFrame();
  void overlayShowsTheSilhouetteItsNodeKeyed();
  void previewMasksComeFromTheFramesMaskOrItsPlate();
  void theSourceSendsEveryFrameOfTheWatchedCamera();
  void aRecordingLeftOpenIsOfferedForRecovery();
  void closingWhileRecordingAsksFirst();
  void bodyChoiceIsRememberedAndHeldWhileThePipelineRuns();
  void aBodyFileIsReadApartAndRefusedSayingWhy();
  void layoutIsRememberedBetweenRuns();
  void healthShowsAKilledNodeLostWithinASecond();
  void theLiveSkeletonBoxStreamsEveryFrameShownToItsReceiver();
  void theLiveViewBoxFeedsTheViewToAReceiver();
};
