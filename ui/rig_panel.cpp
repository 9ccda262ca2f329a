#include "ui/rig_panel.h"

#include <QHeaderView>
#include <QTableWidget>
#include <QVBoxLayout>

#include "ui/stage_plan_view.h"

namespace lumistage {

namespace {

enum Column { kName, kNode, kSize, kFx, kFy, kCx, kCy, kK1, kK2, kX, kY, kZ, kColumns };

}  // namespace

RigPanel::RigPanel(QWidget* parent) : QWidget(parent), table_(new QTableWidget(this)) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->addWidget(table_);
  table_->setColumnCount(kColumns);
  table_->setHorizontalHeaderLabels({tr("Camera"), tr("Node"), tr("Size"), tr("fx"), tr("fy"),
                                     tr("cx"), tr("cy"), tr("k1"), tr("k2"), tr("x (m)"),
                                     tr("y (m)"), tr("z (m)")});
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSelectionMode(QAbstractItemView::SingleSelection);
  table_->verticalHeader()->setVisible(false);
  table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table_->setAlternatingRowColors(true);
  connect(table_, &QTableWidget::itemSelectionChanged, this, [this] {
    const auto rows = table_->selectionModel()->selectedRows();
    emit cameraSelected(rows.isEmpty() ? -1 : rows.first().row());
  });
}

void RigPanel::setRig(const Rig* rig) {
  table_->clearContents();
  table_->setRowCount(rig ? rig->cameraCount() : 0);
  if (!rig) return;
  for (int i = 0; i < rig->cameraCount(); ++i) {
    const Camera& c = rig->camera(i);
    const Intrinsics& k = c.intrinsics();
    const Eigen::Vector3d centre = c.centre();
    auto set = [&](int column, const QString& text, bool numeric = true) {
      auto* item = new QTableWidgetItem(text);
      if (numeric) item->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
      table_->setItem(i, column, item);
    };
    set(kName, QString::fromStdString(c.name()), false);
    set(kNode, QString::fromStdString(c.node()), false);
    table_->item(i, kNode)->setForeground(StagePlanView::nodeColour(rig->nodeOfCamera(i)));
    set(kSize, QString("%1x%2").arg(c.width()).arg(c.height()));
    set(kFx, QString::number(k.fx, 'f', 1));
    set(kFy, QString::number(k.fy, 'f', 1));
    set(kCx, QString::number(k.cx, 'f', 1));
    set(kCy, QString::number(k.cy, 'f', 1));
    set(kK1, QString::number(c.distortion().k1, 'f', 4));
    set(kK2, QString::number(c.distortion().k2, 'f', 4));
    set(kX, QString::number(centre.x(), 'f', 3));
    set(kY, QString::number(centre.y(), 'f', 3));
    set(kZ, QString::number(centre.z(), 'f', 3));
  }
}

}  // namespace lumistage
