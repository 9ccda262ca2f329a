#include "ui/overlay_panel.h"

#include <QCheckBox>
#include <QHBoxLayout>
#include <QListWidget>
#include <QPixmap>
#include <QVBoxLayout>
#include <cstdlib>

namespace lumistage {

OverlayPanel::OverlayPanel(QWidget* parent)
    : QWidget(parent), grid_(new QListWidget(this)), view_(new CameraOverlayView(this)) {
  grid_->setViewMode(QListView::IconMode);
  grid_->setIconSize(QSize(96, 72));
  grid_->setGridSize(QSize(110, 96));
  grid_->setResizeMode(QListView::Adjust);
  grid_->setMovement(QListView::Static);
  grid_->setMaximumWidth(250);
  view_->showSilhouette(true);
  view_->showSkeleton(true);
  view_->showMesh(true);
  auto* toggles = new QHBoxLayout;
  auto toggle = [&](const QString& name, void (CameraOverlayView::*set)(bool)) {
    auto* box = new QCheckBox(name, this);
    box->setChecked(true);
    connect(box, &QCheckBox::toggled, view_, set);
    toggles->addWidget(box);
  };
  toggle(tr("Silhouette"), &CameraOverlayView::showSilhouette);
  toggle(tr("Skeleton"), &CameraOverlayView::showSkeleton);
  toggle(tr("Mesh"), &CameraOverlayView::showMesh);
  toggles->addStretch(1);
  auto* right = new QVBoxLayout;
  right->addLayout(toggles);
  right->addWidget(view_, 1);
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addWidget(grid_);
  layout->addLayout(right, 1);
  connect(grid_, &QListWidget::currentRowChanged, this, [this](int row) { selectCamera(row); });
}

void OverlayPanel::setRig(const Rig& rig) {
  rig_ = rig;
  recent_ = QVector<QVector<Picture>>(rig.cameraCount());
  grid_->clear();
  for (const Camera& c : rig.cameras()) {
    QPixmap blank(96, 72);
    blank.fill(QColor(40, 40, 44));
    grid_->addItem(new QListWidgetItem(QIcon(blank), QString::fromStdString(c.name())));
  }
  selected_ = -1;
  if (rig.cameraCount() > 0) grid_->setCurrentRow(0);
}

bool OverlayPanel::selectCamera(int camera) {
  if (camera < 0 || camera >= rig_.cameraCount()) return false;
  if (camera == selected_) return true;  // also the grid's echo of the row set below
  selected_ = camera;
  if (grid_->currentRow() != camera) grid_->setCurrentRow(camera);
  view_->setCamera(rig_.camera(camera));
  view_->setCaption(tr("%1 (%2): silhouette, skeleton and mesh of the placed body")
                        .arg(QString::fromStdString(rig_.camera(camera).name()),
                             QString::fromStdString(rig_.camera(camera).node())));
  showBestPicture();
  showNodeSilhouette();
  emit cameraSelected(camera);
  return true;
}

void OverlayPanel::showBestPicture() {
  if (selected_ < 0 || selected_ >= recent_.size() || recent_[selected_].isEmpty()) {
    view_->setImage({});
    return;
  }
  const QVector<Picture>& pictures = recent_[selected_];
  const Picture* best = &pictures.back();
  if (pose_frame_ >= 0) {
    for (const Picture& p : pictures) {
      if (std::abs(p.frame_id - pose_frame_) < std::abs(best->frame_id - pose_frame_)) best = &p;
    }
  }
  view_->setImage(best->image, best->mask);
}

// A second of the watched camera's frames at 30 Hz: more than the pipeline's latency, so that the
// frame the latest body was placed for is among them.
constexpr int kRecentPictures = 32;

void OverlayPanel::keepPicture(int camera, const QImage& preview, qint64 frame_id,
                               const QImage& mask) {
  QVector<Picture>& pictures = recent_[camera];
  if (!pictures.isEmpty() && pictures.back().frame_id == frame_id) return;  // came by both signals
  pictures.push_back({frame_id, preview, mask});
  while (pictures.size() > kRecentPictures) pictures.removeFirst();
}

void OverlayPanel::showWatchedFrame(int camera, const QImage& preview, qint64 frame_id,
                                    const QImage& mask) {
  if (camera < 0 || camera >= recent_.size()) return;
  keepPicture(camera, preview, frame_id, mask);
  if (camera == selected_ && pose_frame_ < 0) showBestPicture();
}

void OverlayPanel::showFrame(int camera, const QImage& preview, qint64 frame_id,
                             const QImage& mask) {
  if (camera < 0 || camera >= recent_.size()) return;
  keepPicture(camera, preview, frame_id, mask);
  // The grid's thumbnails once a second are plenty.
  QListWidgetItem* item = grid_->item(camera);
  if (item && (item->data(Qt::UserRole).toLongLong() == 0 ||
               frame_id - item->data(Qt::UserRole).toLongLong() > 25)) {
    item->setData(Qt::UserRole, frame_id);
    item->setIcon(QPixmap::fromImage(preview.scaled(96, 72, Qt::KeepAspectRatio)));
  }
  if (camera == selected_ && pose_frame_ < 0) showBestPicture();
}

void OverlayPanel::showSnapshot(const PipelineSnapshot& s) {
  view_->setBody(s.joints, s.parents, s.mesh);
  pose_frame_ = s.pose_frame;
  silhouettes_ = s.silhouettes;
  showBestPicture();
  showNodeSilhouette();
}

void OverlayPanel::showNodeSilhouette() {
  const LowResSilhouette* keyed = nullptr;
  if (silhouettes_) {
    for (const LowResSilhouette& s : *silhouettes_)
      if (s.camera == selected_) keyed = &s;
  }
  view_->setNodeSilhouette(keyed);
}

}  // namespace lumistage
