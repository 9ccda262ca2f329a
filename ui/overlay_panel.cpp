#include "ui/overlay_panel.h"

#include <QCheckBox>
#include <QHBoxLayout>
#include <QListWidget>
#include <QPixmap>
#include <QVBoxLayout>

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
  latest_ = QVector<QImage>(rig.cameraCount());
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
  selected_ = camera;
  if (grid_->currentRow() != camera) grid_->setCurrentRow(camera);
  view_->setCamera(rig_.camera(camera));
  view_->setCaption(tr("%1 (%2): silhouette, skeleton and mesh of the placed body")
                        .arg(QString::fromStdString(rig_.camera(camera).name()),
                             QString::fromStdString(rig_.camera(camera).node())));
  view_->setImage(latest_[camera]);
  return true;
}

void OverlayPanel::showFrame(int camera, const QImage& preview, qint64) {
  if (camera < 0 || camera >= latest_.size()) return;
  latest_[camera] = preview;
  if (QListWidgetItem* item = grid_->item(camera))
    item->setIcon(QPixmap::fromImage(preview.scaled(96, 72, Qt::KeepAspectRatio)));
  if (camera == selected_) view_->setImage(preview);
}

void OverlayPanel::showSnapshot(const PipelineSnapshot& s) {
  view_->setBody(s.joints, s.parents, s.mesh);
}

}  // namespace lumistage
