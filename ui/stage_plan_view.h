#pragma once

#include <QWidget>

#include "core/geometry/rig.h"

namespace lumistage {

// The stage seen from above: the floor, every camera at its place with its horizontal field of
// view, coloured by node, so that a technician sees at a glance where each camera stands and
// which PC owns it. A camera can be highlighted (selected in the camera list).
class StagePlanView : public QWidget {
  Q_OBJECT

 public:
  explicit StagePlanView(QWidget* parent = nullptr);

  // Not owned; nullptr for none. `stage`: the rig's box (stageVolume), drawn on the floor.
  void setRig(const Rig* rig, const StageBox& stage);
  void setHighlightedCamera(int camera_index);  // -1 for none

  QSize sizeHint() const override { return {640, 560}; }
  // A node's colour, shared with the camera list.
  static QColor nodeColour(int node_index);

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  const Rig* rig_ = nullptr;
  StageBox stage_;
  int highlighted_ = -1;
};

}  // namespace lumistage
