#pragma once

#include <QImage>
#include <QMap>
#include <QString>
#include <QVector>
#include <QWidget>
#include <optional>

#include "core/geometry/rig.h"
#include "ui/camera_overlay_view.h"

class QGridLayout;
class QLabel;

namespace lumistage {

// Per camera reprojection errors of a calibration (RMS, pixels), by camera name.
using ReprojectionErrors = QMap<QString, double>;

// Reads a calibration report (JSON): {"cameras": [{"name": "cam01", "rms_px": 0.21}, ...]}
// ("camera" for "name" and "reprojection_error_px" for "rms_px" are accepted too). Empty
// string on success, else what is wrong in words.
QString loadCalibrationReport(const QString& path, ReprojectionErrors& out);

// Calibration check: every camera's image with its reprojection error (from a calibration
// report when there is one); click a point in one camera and its epipolar lines (bent by the
// lenses) appear in all the others: they must pass through the same point of the scene. The
// cameras' frusta in 3D are drawn in the viewport.
class CalibrationPanel : public QWidget {
  Q_OBJECT

 public:
  explicit CalibrationPanel(QWidget* parent = nullptr);

  void setRig(const Rig& rig);
  void setReprojectionErrors(const ReprojectionErrors& errors);
  // The command behind a click: marks the pixel in `camera` and draws its epipolar curves in the
  // others. False for an unknown camera.
  bool pickPoint(int camera, const Eigen::Vector2d& pixel);
  CameraOverlayView* cameraView(int camera) const { return views_.value(camera); }
  int cameraCount() const { return views_.size(); }

 public slots:
  void showFrame(int camera, const QImage& preview, qint64 frame_id);

 private:
  void refreshCaptions();

  Rig rig_;
  QGridLayout* grid_;
  QLabel* help_;
  QVector<CameraOverlayView*> views_;
  ReprojectionErrors errors_;
};

}  // namespace lumistage
