#pragma once

#include <QImage>
#include <QVector>
#include <QWidget>

#include "core/geometry/rig.h"
#include "ui/camera_overlay_view.h"
#include "ui/pipeline_panel.h"

class QListWidget;

namespace lumistage {

// Skeleton overlay: any camera's image with the actor's silhouette (as its node keyed it while a
// pipeline runs, else as the source keyed the picture), the projected skeleton and the mesh of
// the body the pipeline placed. The camera is picked from a grid of all.
// The picture shown is the camera's preview nearest the frame the body was placed for (the
// studio's previews and the nodes replay a session in step, with the same frame ids): the chosen
// camera's every frame comes (watchedFrame), so on a moving actor the body and the picture are of
// one instant, not up to an eighth of a second apart as with 4 previews a second.
class OverlayPanel : public QWidget {
  Q_OBJECT

 public:
  explicit OverlayPanel(QWidget* parent = nullptr);

  void setRig(const Rig& rig);
  bool selectCamera(int camera);  // false for an unknown camera
  int selectedCamera() const { return selected_; }
  CameraOverlayView* view() const { return view_; }

 signals:
  void cameraSelected(int camera);

 public slots:
  // `mask`: the source's mask of the actor in the preview (SourceWorker::previewMask; null: the
  // picture is keyed green).
  void showFrame(int camera, const QImage& preview, qint64 frame_id, const QImage& mask = {});
  // The chosen camera's every frame (SourceWorker::watchedFrame).
  void showWatchedFrame(int camera, const QImage& preview, qint64 frame_id,
                        const QImage& mask = {});
  void showSnapshot(const lumistage::PipelineSnapshot& snapshot);

 private:
  Rig rig_;
  QListWidget* grid_;
  CameraOverlayView* view_;
  void showBestPicture();
  void keepPicture(int camera, const QImage& preview, qint64 frame_id, const QImage& mask);

  struct Picture {
    qint64 frame_id;
    QImage image, mask;
  };
  QVector<QVector<Picture>> recent_;  // per camera, its latest previews
  int selected_ = -1;
  qint64 pose_frame_ = -1;
  // The silhouettes the nodes keyed for pose_frame_ (null: none, the picture's green key shown).
  std::shared_ptr<const std::vector<LowResSilhouette>> silhouettes_;
  void showNodeSilhouette();
};

}  // namespace lumistage
