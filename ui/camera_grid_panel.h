#pragma once

#include <QElapsedTimer>
#include <QVector>
#include <QWidget>

#include "core/geometry/rig.h"
#include "ui/source_worker.h"

class QGridLayout;
class QLabel;

namespace lumistage {

// Every camera's live picture with its health: frame rate, drops, and a state a technician reads
// at a glance — streaming (green), late (amber: nothing for half a second), lost (red: nothing
// for two seconds), with the camera's last error in words.
class CameraGridPanel : public QWidget {
  Q_OBJECT

 public:
  explicit CameraGridPanel(QWidget* parent = nullptr);

  void setRig(const Rig& rig);
  int cameraCount() const { return tiles_.size(); }
  int camerasWithPictures() const;
  // "streaming", "late", "lost" or "waiting" (no frame yet).
  QString state(int camera) const;

 public slots:
  void showFrame(int camera, const QImage& preview, qint64 frame_id);
  void showStatus(const QVector<lumistage::CameraStatus>& cameras);

 private:
  struct Tile {
    QLabel* picture = nullptr;
    QLabel* caption = nullptr;
    QString name;
    bool has_frame = false;
    QElapsedTimer since_frame;  // meaningful once has_frame
    CameraStatus status;
  };
  void refreshCaptions();
  void refreshCaption(int camera);

  QGridLayout* grid_;
  QVector<Tile> tiles_;
};

}  // namespace lumistage
