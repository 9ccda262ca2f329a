#include "ui/camera_grid_panel.h"

#include <QGridLayout>
#include <QLabel>
#include <QPixmap>
#include <QTimer>
#include <cmath>

#include "core/pipeline/camera_health.h"

namespace lumistage {

CameraGridPanel::CameraGridPanel(QWidget* parent) : QWidget(parent), grid_(new QGridLayout(this)) {
  grid_->setSpacing(6);
  auto* timer = new QTimer(this);  // states age even when no frame arrives
  connect(timer, &QTimer::timeout, this, &CameraGridPanel::refreshCaptions);
  timer->start(250);
}

void CameraGridPanel::setRig(const Rig& rig) {
  for (Tile& t : tiles_) {
    delete t.picture;
    delete t.caption;
  }
  tiles_.clear();
  const int columns = rig.cameraCount() <= 4 ? rig.cameraCount() : (rig.cameraCount() <= 9 ? 3 : 4);
  for (int c = 0; c < rig.cameraCount(); ++c) {
    Tile tile;
    tile.name = QString::fromStdString(rig.camera(c).name() + " (" + rig.camera(c).node() + ")");
    tile.picture = new QLabel(this);
    tile.picture->setMinimumSize(96, 72);  // 12 tiles in a 1366x768 laptop's window
    // The picture follows the tile, not the other way round (a label sizes itself to its pixmap:
    // the grid then held the window 1800 pixels wide).
    tile.picture->setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Ignored);
    tile.picture->setAlignment(Qt::AlignCenter);
    tile.picture->setStyleSheet("background: #111; color: #aaa;");
    tile.picture->setText(tr("waiting for frames"));
    tile.caption = new QLabel(this);
    tile.caption->setWordWrap(true);
    const int row = 2 * (c / columns), column = c % columns;
    grid_->addWidget(tile.picture, row, column);
    grid_->addWidget(tile.caption, row + 1, column);
    tiles_.push_back(tile);
  }
  refreshCaptions();
}

int CameraGridPanel::camerasWithPictures() const {
  int n = 0;
  for (const Tile& t : tiles_) n += t.has_frame;
  return n;
}

QString CameraGridPanel::state(int camera) const {
  const Tile& t = tiles_.at(camera);
  if (!t.has_frame) return "waiting";
  // The thresholds of the camera health panel: the two tabs never disagree about a camera.
  HealthInput input;
  input.silent_ms = double(t.since_frame.elapsed());
  return healthStateName(classifyHealth(input).state);
}

void CameraGridPanel::showFrame(int camera, const QImage& preview, qint64) {
  if (camera < 0 || camera >= tiles_.size()) return;
  Tile& t = tiles_[camera];
  t.picture->setPixmap(QPixmap::fromImage(preview).scaled(t.picture->size(), Qt::KeepAspectRatio,
                                                          Qt::SmoothTransformation));
  t.since_frame.restart();
  t.has_frame = true;
  refreshCaption(camera);
}

void CameraGridPanel::showStatus(const QVector<CameraStatus>& cameras) {
  for (int c = 0; c < cameras.size() && c < tiles_.size(); ++c) tiles_[c].status = cameras[c];
  refreshCaptions();
}

void CameraGridPanel::refreshCaptions() {
  for (int c = 0; c < tiles_.size(); ++c) refreshCaption(c);
}

void CameraGridPanel::refreshCaption(int c) {
  {
    Tile& t = tiles_[c];
    const QString s = state(c);
    const char* colour = s == "streaming" ? "#3c3"
                         : s == "late"    ? "#e90"
                         : s == "lost"    ? "#e33"
                                          : "#888";
    QString text = QString(
                       "<b>%1</b> <span style='color:%2'>&#9679; %3</span> &middot; %4 fps "
                       "&middot; %5 dropped")
                       .arg(t.name, colour, s)
                       .arg(t.status.frame_rate_hz, 0, 'f', 1)
                       .arg(t.status.dropped);
    if (!t.status.last_error.isEmpty())
      text += "<br><span style='color:#e33'>" + t.status.last_error.toHtmlEscaped() + "</span>";
    t.caption->setText(text);
  }
}

}  // namespace lumistage
