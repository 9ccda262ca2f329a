#pragma once

#include <QWidget>

#include "core/render/clone_set.h"

class QListWidget;
class QPushButton;

namespace lumistage {

// Actor cloning: the list of clones with add, turn and remove; clones are dragged in the
// viewport (Shift+drag moves one, Ctrl+drag turns it).
class ClonePanel : public QWidget {
  Q_OBJECT

 public:
  explicit ClonePanel(CloneSet* clones, QWidget* parent = nullptr);

  QListWidget* list() const { return list_; }
  int selectedId() const;  // 0 when none
  // Commands, as the buttons do them (the new clone: 1.2 m to the side of the previous one).
  int addClone();
  bool removeSelected();
  bool turnSelected(double yaw_rad);

 public slots:
  void refresh();  // after the set changed elsewhere (the viewport)

 signals:
  void clonesChanged();

 private:
  CloneSet* clones_;
  QListWidget* list_;
  QPushButton* add_button_;
};

}  // namespace lumistage
