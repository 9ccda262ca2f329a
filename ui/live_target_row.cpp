#include "ui/live_target_row.h"

#include <QCheckBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QSettings>
#include <QSignalBlocker>

namespace lumistage {

LiveTargetRow::LiveTargetRow(const LiveTargetRowSpec& spec, QWidget* parent)
    : QWidget(parent),
      setting_(spec.setting),
      box_(new QCheckBox(spec.label, this)),
      target_(new QLineEdit(this)),
      status_(new QLabel(this)) {
  box_->setObjectName(spec.box_name);
  box_->setToolTip(spec.box_tip);
  target_->setObjectName(spec.target_name);
  target_->setToolTip(spec.target_tip);
  target_->setText(
      QSettings("Lumistage", "Studio").value(spec.setting, spec.default_target).toString());
  target_->setMinimumWidth(spec.target_min_width);
  target_->setMaximumWidth(spec.target_max_width);
  status_->setObjectName(spec.status_name);
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->addWidget(box_);
  layout->addWidget(target_);
  layout->addWidget(status_);
  connect(box_, &QCheckBox::toggled, this, [this] {
    status_->clear();
    status_->setToolTip({});
    emit toggled();
  });
  // Another target, typed while the output runs: Enter moves it there.
  connect(target_, &QLineEdit::returnPressed, this, [this] {
    if (box_->isChecked()) emit toggled();
  });
}

QString LiveTargetRow::checkedTarget() const {
  return box_->isChecked() ? target_->text().trimmed() : QString();
}

void LiveTargetRow::rememberTarget() const {
  QSettings("Lumistage", "Studio").setValue(setting_, target_->text().trimmed());
}

void LiveTargetRow::failed(const QString& why, const QString& briefly) {
  {
    const QSignalBlocker quiet(box_);  // unchecked here: nothing to stop
    box_->setChecked(false);
  }
  // A few words on the row, the whole of it on hovering (the row has no room for a sentence).
  const QString words = briefly.isEmpty() ? tr("not sent") : tr("not sent: %1").arg(briefly);
  status_->setText("<b style='color:#e33'>" + words.toHtmlEscaped() + "</b>");
  status_->setToolTip(why);
}

void LiveTargetRow::showStatus(const QString& text, const QString& tip) {
  if (text.isEmpty() && status_->text().startsWith("<b")) return;
  status_->setText(text);
  status_->setToolTip(tip);
}

}  // namespace lumistage
