#include "ui/camera_overlay_view.h"

#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <algorithm>

namespace lumistage {

CameraOverlayView::CameraOverlayView(QWidget* parent) : QWidget(parent) {
  setMinimumSize(96, 72);  // 12 of them in a 1366x768 laptop's window
  setCursor(Qt::CrossCursor);
}

void CameraOverlayView::setCamera(const Camera& camera) {
  camera_ = camera;
  update();
}

namespace {

constexpr QRgb kActorTint = qRgba(255, 60, 200, 110);

}  // namespace

void CameraOverlayView::setImage(const QImage& image, const QImage& mask) {
  image_ = image;
  picture_mask_ = mask;
  if (!node_silhouette_) mask_ = silhouette_ ? pictureSilhouette() : QImage();
  update();
}

QImage CameraOverlayView::pictureSilhouette() const {
  if (image_.isNull()) return {};
  if (picture_mask_.isNull()) return keySilhouette(image_);
  const QImage grey = picture_mask_.convertToFormat(QImage::Format_Grayscale8);
  QImage tinted(grey.size(), QImage::Format_ARGB32);
  for (int y = 0; y < grey.height(); ++y) {
    const uchar* in = grey.constScanLine(y);
    auto* out = reinterpret_cast<QRgb*>(tinted.scanLine(y));
    for (int x = 0; x < grey.width(); ++x) out[x] = in[x] ? kActorTint : qRgba(0, 0, 0, 0);
  }
  return tinted;
}

void CameraOverlayView::setNodeSilhouette(const LowResSilhouette* silhouette) {
  node_silhouette_ = silhouette && silhouette->width > 0 && silhouette->height > 0;
  if (!node_silhouette_) {
    mask_ = silhouette_ ? pictureSilhouette() : QImage();
    update();
    return;
  }
  const LowResSilhouette& s = *silhouette;
  mask_ = QImage(s.width, s.height, QImage::Format_ARGB32);
  for (int y = 0; y < s.height; ++y) {
    auto* out = reinterpret_cast<QRgb*>(mask_.scanLine(y));
    for (int x = 0; x < s.width; ++x) out[x] = s.at(x, y) ? kActorTint : qRgba(0, 0, 0, 0);
  }
  mask_span_ = QSizeF(s.width * s.step, s.height * s.step);
  update();
}

void CameraOverlayView::setCaption(const QString& caption) {
  caption_ = caption;
  update();
}

void CameraOverlayView::setBody(const std::vector<Eigen::Vector3d>& joints,
                                const std::vector<int>& parents,
                                std::shared_ptr<const TriangleMesh> mesh) {
  joints_ = joints;
  parents_ = parents;
  mesh_ = std::move(mesh);
  update();
}

QImage CameraOverlayView::keySilhouette(const QImage& image, int threshold) {
  const QImage rgb = image.convertToFormat(QImage::Format_RGB888);
  QImage mask(rgb.size(), QImage::Format_ARGB32);
  for (int y = 0; y < rgb.height(); ++y) {
    const uchar* in = rgb.constScanLine(y);
    auto* out = reinterpret_cast<QRgb*>(mask.scanLine(y));
    for (int x = 0; x < rgb.width(); ++x) {
      const int r = in[3 * x], g = in[3 * x + 1], b = in[3 * x + 2];
      const bool actor = g - std::max(r, b) < threshold;
      out[x] = actor ? kActorTint : qRgba(0, 0, 0, 0);
    }
  }
  return mask;
}

QRectF CameraOverlayView::imageRect() const {
  const double cw = std::max(1, camera_.width()), ch = std::max(1, camera_.height());
  const double top = 18;
  const double s = std::min(width() / cw, (height() - top) / ch);
  return QRectF((width() - cw * s) / 2, top + (height() - top - ch * s) / 2, cw * s, ch * s);
}

void CameraOverlayView::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), QColor(20, 20, 22));
  painter.setPen(QColor(220, 220, 220));
  painter.drawText(QRectF(4, 0, width() - 8, 18), Qt::AlignLeft | Qt::AlignVCenter, caption_);
  if (camera_.width() <= 0) return;
  const QRectF r = imageRect();
  if (!image_.isNull()) {
    painter.drawImage(r, image_);
  } else {
    painter.fillRect(r, QColor(40, 40, 44));
    painter.drawText(r, Qt::AlignCenter, tr("waiting for frames"));
  }
  if (silhouette_) {
    if (mask_.isNull() && !node_silhouette_) mask_ = pictureSilhouette();
    if (!mask_.isNull() && node_silhouette_) {
      // Cells over the camera's pixels they cover, each a sharp square.
      const QRectF cells(r.topLeft(), QSizeF(r.width() * mask_span_.width() / camera_.width(),
                                             r.height() * mask_span_.height() / camera_.height()));
      painter.save();
      painter.setRenderHint(QPainter::SmoothPixmapTransform, false);
      painter.drawImage(cells, mask_);
      painter.restore();
    } else if (!mask_.isNull()) {
      painter.drawImage(r, mask_);
    }
  }
  const double sx = r.width() / camera_.width(), sy = r.height() / camera_.height();
  auto map = [&](const Eigen::Vector2d& p) {
    return QPointF(r.left() + (p.x() + 0.5) * sx, r.top() + (p.y() + 0.5) * sy);
  };
  auto project = [&](const Eigen::Vector3d& p) -> std::optional<QPointF> {
    const std::optional<Eigen::Vector2d> px = camera_.project(p);
    if (!px) return std::nullopt;
    return map(*px);
  };
  painter.setClipRect(r);
  if (mesh_on_ && mesh_) {
    std::vector<std::optional<QPointF>> px(mesh_->vertexCount());
    for (int v = 0; v < mesh_->vertexCount(); ++v)
      px[v] = project(mesh_->positions.col(v).cast<double>());
    painter.setPen(QPen(QColor(80, 200, 255, 120), 0.6));
    for (const Eigen::Vector3i& t : mesh_->triangles) {
      for (int k = 0; k < 3; ++k) {
        const auto& a = px[t[k]];
        const auto& b = px[t[(k + 1) % 3]];
        if (a && b) painter.drawLine(*a, *b);
      }
    }
  }
  if (skeleton_ && joints_.size() == parents_.size()) {
    painter.setPen(QPen(QColor(255, 210, 40), 2.5));
    for (size_t j = 0; j < joints_.size(); ++j) {
      if (parents_[j] < 0) continue;
      const auto a = project(joints_[j]), b = project(joints_[parents_[j]]);
      if (a && b) painter.drawLine(*a, *b);
    }
    painter.setBrush(QColor(255, 120, 40));
    for (const Eigen::Vector3d& j : joints_) {
      if (const auto p = project(j)) painter.drawEllipse(*p, 3, 3);
    }
  }
  painter.setPen(QPen(QColor(255, 80, 80), 1.8));
  for (const auto& curve : curves_) {
    QPainterPath path;
    for (size_t i = 0; i < curve.size(); ++i) {
      if (i == 0) {
        path.moveTo(map(curve[i]));
      } else {
        path.lineTo(map(curve[i]));
      }
    }
    painter.setBrush(Qt::NoBrush);
    painter.drawPath(path);
  }
  if (marker_) {
    painter.setPen(QPen(QColor(255, 255, 0), 2));
    const QPointF p = map(*marker_);
    painter.drawLine(p - QPointF(8, 0), p + QPointF(8, 0));
    painter.drawLine(p - QPointF(0, 8), p + QPointF(0, 8));
  }
}

void CameraOverlayView::mousePressEvent(QMouseEvent* event) {
  if (camera_.width() <= 0) return;
  const QRectF r = imageRect();
  const QPointF p = event->position();
  if (!r.contains(p)) return;
  emit clicked(Eigen::Vector2d((p.x() - r.left()) / r.width() * camera_.width() - 0.5,
                               (p.y() - r.top()) / r.height() * camera_.height() - 0.5));
}

}  // namespace lumistage
