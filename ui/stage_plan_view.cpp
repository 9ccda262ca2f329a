#include "ui/stage_plan_view.h"

#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace lumistage {

StagePlanView::StagePlanView(QWidget* parent) : QWidget(parent) {
  setMinimumSize(240, 200);
  setAutoFillBackground(false);
}

void StagePlanView::setRig(const Rig* rig, const StageBox& stage) {
  rig_ = rig;
  stage_ = stage;
  highlighted_ = -1;
  update();
}

void StagePlanView::setHighlightedCamera(int camera_index) {
  highlighted_ = camera_index;
  update();
}

QColor StagePlanView::nodeColour(int node_index) {
  static const QColor kColours[] = {{0xf2, 0x8e, 0x2b}, {0x4e, 0x9a, 0xf0}, {0xe1, 0x57, 0x59},
                                    {0x76, 0xd7, 0xc4}, {0xed, 0xc9, 0x48}, {0xb0, 0x7a, 0xe1},
                                    {0xff, 0x9d, 0xa7}, {0x9c, 0xde, 0x5c}};
  return kColours[std::abs(node_index) % 8];
}

void StagePlanView::paintEvent(QPaintEvent*) {
  QPainter p(this);
  p.setRenderHint(QPainter::Antialiasing);
  p.fillRect(rect(), QColor(0x1e, 0x20, 0x24));

  // World extent to show: the stage and every camera, with a margin for labels.
  const Eigen::Vector3d& lo = stage_.lower;
  const Eigen::Vector3d& hi = stage_.upper;
  double half_x = std::max(-lo.x(), hi.x()), half_y = std::max(-lo.y(), hi.y());
  if (rig_) {
    for (const Camera& c : rig_->cameras()) {
      half_x = std::max(half_x, std::abs(c.centre().x()));
      half_y = std::max(half_y, std::abs(c.centre().y()));
    }
  }
  half_x += 0.8;
  half_y += 0.8;
  const double scale = std::min(width() / (2 * half_x), height() / (2 * half_y));
  // World x to the right, world y up on screen.
  auto toScreen = [&](double x, double y) {
    return QPointF(width() / 2.0 + x * scale, height() / 2.0 - y * scale);
  };

  // Floor: the stage the actor is tracked on, with a half-metre grid.
  const QRectF stage(toScreen(lo.x(), hi.y()), toScreen(hi.x(), lo.y()));
  p.fillRect(stage, QColor(0x2f, 0x7d, 0x3a));
  p.setPen(QPen(QColor(255, 255, 255, 40), 1));
  for (double x = lo.x(); x <= hi.x() + 1e-9; x += 0.5) {
    p.drawLine(toScreen(x, lo.y()), toScreen(x, hi.y()));
  }
  for (double y = lo.y(); y <= hi.y() + 1e-9; y += 0.5) {
    p.drawLine(toScreen(lo.x(), y), toScreen(hi.x(), y));
  }
  p.setPen(QPen(QColor(255, 255, 255, 160), 1.5));
  p.drawRect(stage);
  // World axes at the stage centre: x red, y green.
  p.setPen(QPen(QColor(0xe0, 0x50, 0x50), 2));
  p.drawLine(toScreen(0, 0), toScreen(0.5, 0));
  p.setPen(QPen(QColor(0x60, 0xe0, 0x60), 2));
  p.drawLine(toScreen(0, 0), toScreen(0, 0.5));

  if (!rig_ || rig_->cameraCount() == 0) {
    p.setPen(QColor(220, 220, 220));
    p.drawText(rect(), Qt::AlignCenter, tr("No rig loaded: File > Open rig..."));
    return;
  }

  QFont font = p.font();
  font.setPointSizeF(font.pointSizeF() * 0.9);
  p.setFont(font);
  for (int i = 0; i < rig_->cameraCount(); ++i) {
    const Camera& c = rig_->camera(i);
    const QColor colour = nodeColour(rig_->nodeOfCamera(i));
    const bool highlighted = i == highlighted_;
    const Eigen::Vector3d centre = c.centre();
    // Horizontal field of view as a wedge on the floor plan, 1.5 m long (to the far edge when
    // highlighted).
    const Eigen::Vector3d forward = c.viewingDirection();
    const double heading = std::atan2(forward.y(), forward.x());
    const double half_fov = std::atan2(0.5 * c.width(), c.intrinsics().fx);
    const double reach = highlighted ? 2 * std::hypot(half_x, half_y) : 1.5;
    QPainterPath wedge;
    wedge.moveTo(toScreen(centre.x(), centre.y()));
    for (double a : {heading - half_fov, heading + half_fov}) {
      wedge.lineTo(toScreen(centre.x() + reach * std::cos(a), centre.y() + reach * std::sin(a)));
    }
    wedge.closeSubpath();
    QColor fill = colour;
    fill.setAlpha(highlighted ? 90 : 35);
    p.fillPath(wedge, fill);
    p.setBrush(Qt::NoBrush);
    p.setPen(QPen(colour, highlighted ? 2.5 : 1.2));
    p.drawPath(wedge);

    const QPointF at = toScreen(centre.x(), centre.y());
    const double radius = highlighted ? 8 : 6;
    p.setBrush(colour);
    p.setPen(QPen(Qt::white, highlighted ? 2 : 1));
    p.drawEllipse(at, radius, radius);
    // Label outside the ring, with the camera's height.
    const QPointF outward(std::cos(heading + std::numbers::pi),
                          -std::sin(heading + std::numbers::pi));
    // Beside the dot, away from the stage: further out sideways, where the text's width lies.
    const QPointF label_at = at + outward * 24 + QPointF(outward.x() * 36, 0);
    const QString label =
        QString("%1  %2 m").arg(QString::fromStdString(c.name())).arg(centre.z(), 0, 'f', 1);
    const QRectF box(label_at.x() - 50, label_at.y() - 9, 100, 18);
    p.setPen(highlighted ? Qt::white : QColor(220, 220, 220));
    p.drawText(box, Qt::AlignCenter, label);
  }

  // Legend: one line per node.
  p.setBrush(Qt::NoBrush);
  double y = 16;
  for (int n = 0; n < rig_->nodeCount(); ++n) {
    const RigNode& node = rig_->nodes()[n];
    p.setPen(Qt::NoPen);
    p.setBrush(nodeColour(n));
    p.drawEllipse(QPointF(14, y), 5, 5);
    p.setBrush(Qt::NoBrush);
    p.setPen(QColor(230, 230, 230));
    p.drawText(QPointF(26, y + 4), QString("%1  (%2 cameras)")
                                       .arg(QString::fromStdString(node.name))
                                       .arg(node.cameras.size()));
    y += 18;
  }
}

}  // namespace lumistage
