#include "ui/calibration_panel.h"

#include <QFile>
#include <QGridLayout>
#include <QJsonArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <QLabel>
#include <QVBoxLayout>

#include "core/calib/calibration_report.h"
#include "core/geometry/epipolar.h"

namespace lumistage {

QString loadCalibrationReport(const QString& path, ReprojectionErrors& out) {
  if (path.endsWith(".yaml") || path.endsWith(".yml")) {
    // What `lumistage calibrate` writes (docs/calibration.md).
    try {
      const CalibrationReport report = loadCalibrationReport(path.toStdString());
      out.clear();
      for (const CameraCalibrationReport& c : report.cameras)
        out[QString::fromStdString(c.name)] = c.rms_px;
    } catch (const std::exception& e) {
      return QString::fromStdString(e.what());
    }
    return {};
  }
  QFile file(path);
  if (!file.open(QIODevice::ReadOnly)) return QObject::tr("%1: cannot open").arg(path);
  QJsonParseError error;
  const QJsonDocument doc = QJsonDocument::fromJson(file.readAll(), &error);
  if (doc.isNull()) {
    return QObject::tr("%1: not JSON (%2 at offset %3)")
        .arg(path, error.errorString())
        .arg(error.offset);
  }
  const QJsonValue cameras = doc.object().value("cameras");
  if (!cameras.isArray()) return QObject::tr("%1: expected a \"cameras\" array").arg(path);
  out.clear();
  for (const QJsonValue& v : cameras.toArray()) {
    const QJsonObject o = v.toObject();
    const QString name =
        o.contains("name") ? o.value("name").toString() : o.value("camera").toString();
    const QJsonValue rms =
        o.contains("rms_px") ? o.value("rms_px") : o.value("reprojection_error_px");
    if (name.isEmpty() || !rms.isDouble()) {
      return QObject::tr("%1: each camera needs a \"name\" and an \"rms_px\" number").arg(path);
    }
    out[name] = rms.toDouble();
  }
  return {};
}

CalibrationPanel::CalibrationPanel(QWidget* parent)
    : QWidget(parent), grid_(new QGridLayout), help_(new QLabel(this)) {
  help_->setWordWrap(true);
  help_->setText(
      tr("Click a point in a camera: its epipolar line (red) in the others passes through the "
         "same point on a good calibration. Errors: from RIG.calibration.yaml beside the rig."));
  help_->setToolTip(
      tr("Reprojection errors come from the rig's calibration report beside the rig file "
         "(RIG.calibration.yaml, as lumistage calibrate writes it, or calibration_report.json)."));
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addWidget(help_);
  layout->addLayout(grid_, 1);
  grid_->setSpacing(4);
}

void CalibrationPanel::setRig(const Rig& rig) {
  qDeleteAll(views_);
  views_.clear();
  rig_ = rig;
  const int columns = rig.cameraCount() <= 4 ? std::max(1, rig.cameraCount()) : 4;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    auto* view = new CameraOverlayView(this);
    view->setCamera(rig.camera(c));
    grid_->addWidget(view, c / columns, c % columns);
    connect(view, &CameraOverlayView::clicked, this,
            [this, c](const Eigen::Vector2d& pixel) { pickPoint(c, pixel); });
    views_.push_back(view);
  }
  refreshCaptions();
}

void CalibrationPanel::setReprojectionErrors(const ReprojectionErrors& errors) {
  errors_ = errors;
  refreshCaptions();
}

void CalibrationPanel::refreshCaptions() {
  for (int c = 0; c < views_.size(); ++c) {
    const QString name = QString::fromStdString(rig_.camera(c).name());
    const auto it = errors_.find(name);
    views_[c]->setCaption(it == errors_.end()
                              ? tr("%1: reprojection error not measured").arg(name)
                              : tr("%1: reprojection error %2 px").arg(name).arg(*it, 0, 'f', 2));
  }
}

bool CalibrationPanel::pickPoint(int camera, const Eigen::Vector2d& pixel) {
  if (camera < 0 || camera >= views_.size()) return false;
  for (int c = 0; c < views_.size(); ++c) {
    if (c == camera) {
      views_[c]->setMarker(pixel);
      views_[c]->setCurves({});
    } else {
      views_[c]->setMarker(std::nullopt);
      views_[c]->setCurves(
          {epipolarCurve(rig_.camera(camera), pixel, rig_.camera(c), 0.3, 30.0, 3.0)});
    }
  }
  return true;
}

void CalibrationPanel::showFrame(int camera, const QImage& preview, qint64) {
  if (camera >= 0 && camera < views_.size()) views_[camera]->setImage(preview);
}

}  // namespace lumistage
