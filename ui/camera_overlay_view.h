#pragma once

#include <QImage>
#include <QWidget>
#include <memory>
#include <optional>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/geometry/camera.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

// One camera's image with overlays drawn in its own pixels: the actor's silhouette (the cells its
// node keyed, or else the source's mask of the picture, or else the picture's green key), the
// projected skeleton and mesh, epipolar curves and a marked point. Clicks come out in the camera's
// pixels.
class CameraOverlayView : public QWidget {
  Q_OBJECT

 public:
  explicit CameraOverlayView(QWidget* parent = nullptr);

  void setCamera(const Camera& camera);
  const Camera& camera() const { return camera_; }
  // Any size: stretched over the camera's pixels. `mask` (8 bits, 255 on the actor; null: the
  // picture's green key): the source's mask of the actor in it, from another tool or a plate.
  void setImage(const QImage& image, const QImage& mask = {});
  // The silhouette its node keyed (whatever it keys on: green, a clean plate, a session's masks),
  // drawn cell by cell instead of the picture's; null: the picture's again (setImage's mask, else
  // its green key).
  void setNodeSilhouette(const LowResSilhouette* silhouette);
  bool showsNodeSilhouette() const { return node_silhouette_; }
  // The silhouette layer's mask: one pixel a cell of the node's silhouette, or the picture's (its
  // source's mask, else its green key) at its size (transparent where not the actor); null when
  // there is none.
  const QImage& silhouetteMask() const { return mask_; }
  bool hasImage() const { return !image_.isNull(); }
  const QImage& image() const { return image_; }
  void setCaption(const QString& caption);
  const QString& caption() const { return caption_; }
  void showSilhouette(bool on) {
    silhouette_ = on;
    update();
  }
  void showSkeleton(bool on) {
    skeleton_ = on;
    update();
  }
  void showMesh(bool on) {
    mesh_on_ = on;
    update();
  }
  void setBody(const std::vector<Eigen::Vector3d>& joints, const std::vector<int>& parents,
               std::shared_ptr<const TriangleMesh> mesh);
  void setCurves(std::vector<std::vector<Eigen::Vector2d>> curves) {
    curves_ = std::move(curves);
    update();
  }
  void setMarker(std::optional<Eigen::Vector2d> pixel) {
    marker_ = pixel;
    update();
  }
  const std::vector<std::vector<Eigen::Vector2d>>& curves() const { return curves_; }
  const std::optional<Eigen::Vector2d>& marker() const { return marker_; }
  // The actor's mask of the image (255 where the green-screen key says actor), at image size.
  static QImage keySilhouette(const QImage& image, int threshold = 30);

 signals:
  void clicked(Eigen::Vector2d pixel);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;

 private:
  QRectF imageRect() const;  // where the camera's pixels go in the widget

  Camera camera_;
  QImage image_, mask_;
  QImage picture_mask_;              // setImage's mask
  QImage pictureSilhouette() const;  // the tinted picture_mask_, else the picture's green key
  QString caption_;
  bool silhouette_ = false, skeleton_ = false, mesh_on_ = false;
  bool node_silhouette_ = false;  // mask_ is a node's silhouette (setNodeSilhouette)
  QSizeF mask_span_;              // the camera pixels mask_ covers (a node's cells may stop short)
  std::vector<Eigen::Vector3d> joints_;
  std::vector<int> parents_;
  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<std::vector<Eigen::Vector2d>> curves_;
  std::optional<Eigen::Vector2d> marker_;
};

}  // namespace lumistage
