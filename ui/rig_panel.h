#pragma once

#include <QWidget>

#include "core/geometry/rig.h"

class QTableWidget;

namespace lumistage {

// The camera list: every camera with its node, image size, intrinsics, lens and position. Picking
// a row emits cameraSelected so other views can highlight the camera.
class RigPanel : public QWidget {
  Q_OBJECT

 public:
  explicit RigPanel(QWidget* parent = nullptr);

  void setRig(const Rig* rig);  // not owned; nullptr for none
  QTableWidget* table() const { return table_; }

 signals:
  void cameraSelected(int camera_index);  // -1 when the selection is cleared

 private:
  QTableWidget* table_;
};

}  // namespace lumistage
