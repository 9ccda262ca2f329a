#include "ui/clone_panel.h"

#include <QHBoxLayout>
#include <QListWidget>
#include <QPushButton>
#include <QVBoxLayout>
#include <cmath>

namespace lumistage {

ClonePanel::ClonePanel(CloneSet* clones, QWidget* parent)
    : QWidget(parent), clones_(clones), list_(new QListWidget(this)) {
  auto* add = add_button_ = new QPushButton(tr("Add clone"), this);
  auto* remove = new QPushButton(tr("Remove"), this);
  auto* left = new QPushButton(tr("Turn left"), this);
  auto* right = new QPushButton(tr("Turn right"), this);
  auto* buttons = new QHBoxLayout;
  for (QPushButton* b : {add, remove, left, right}) buttons->addWidget(b);
  buttons->addStretch(1);
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addLayout(buttons);
  layout->addWidget(list_, 1);
  connect(add, &QPushButton::clicked, this, &ClonePanel::addClone);
  connect(remove, &QPushButton::clicked, this, &ClonePanel::removeSelected);
  connect(left, &QPushButton::clicked, this, [this] { turnSelected(M_PI / 8); });
  connect(right, &QPushButton::clicked, this, [this] { turnSelected(-M_PI / 8); });
}

int ClonePanel::selectedId() const {
  const QListWidgetItem* item = list_->currentItem();
  return item ? item->data(Qt::UserRole).toInt() : 0;
}

int ClonePanel::addClone() {
  const int n = static_cast<int>(clones_->clones().size());
  // Alternate sides, further out each time.
  const double side = (n % 2 == 0 ? 1 : -1) * 1.2 * (n / 2 + 1);
  const int id = clones_->add({0, side});
  if (id == 0) return 0;  // as many as the nodes take; the button is disabled
  refresh();
  for (int r = 0; r < list_->count(); ++r) {
    if (list_->item(r)->data(Qt::UserRole).toInt() == id) list_->setCurrentRow(r);
  }
  emit clonesChanged();
  return id;
}

bool ClonePanel::removeSelected() {
  const bool removed = clones_->remove(selectedId());
  refresh();
  if (removed) emit clonesChanged();
  return removed;
}

bool ClonePanel::turnSelected(double yaw_rad) {
  const bool turned = clones_->rotateBy(selectedId(), yaw_rad);
  refresh();
  if (turned) emit clonesChanged();
  return turned;
}

void ClonePanel::refresh() {
  const int selected = selectedId();
  list_->clear();
  for (const Clone& c : clones_->clones()) {
    auto* item = new QListWidgetItem(tr("%1: offset (%2, %3) m, turned %4 deg")
                                         .arg(QString::fromStdString(c.name))
                                         .arg(c.offset_m.x(), 0, 'f', 2)
                                         .arg(c.offset_m.y(), 0, 'f', 2)
                                         .arg(c.yaw_rad * 180 / M_PI, 0, 'f', 0));
    item->setData(Qt::UserRole, c.id);
    list_->addItem(item);
    if (c.id == selected) list_->setCurrentItem(item);
  }
  const bool full = int(clones_->clones().size()) >= CloneSet::kMaxClones;
  add_button_->setEnabled(!full);
  add_button_->setToolTip(full ? tr("At most %1 clones").arg(CloneSet::kMaxClones) : QString());
}

}  // namespace lumistage
