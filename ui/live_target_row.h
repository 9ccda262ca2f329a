#pragma once

#include <QString>
#include <QWidget>

class QCheckBox;
class QLabel;
class QLineEdit;

namespace lumistage {

// What a live output's row shows: the check box's label, name and tooltip, the target's field
// (its name, tooltip, width and default), the settings key that remembers it, the status' name.
struct LiveTargetRowSpec {
  QString label, box_name, box_tip;
  QString target_name, target_tip, default_target;
  int target_min_width = 150, target_max_width = 170;
  QString setting;  // e.g. "pipeline/osc"
  QString status_name;
};

// One live output of the pipeline panel (the skeleton over OSC, the view as a video feed): a
// check box, its target, remembered between sessions, and a status beside them. Checked while the
// pipeline runs, the output runs; the panel asks its worker on toggled().
class LiveTargetRow : public QWidget {
  Q_OBJECT

 public:
  LiveTargetRow(const LiveTargetRowSpec& spec, QWidget* parent);
  // The target's text, trimmed, while the box is checked; empty otherwise.
  QString checkedTarget() const;
  // The target's text taken for the next session (once it proved one).
  void rememberTarget() const;
  // The output could not start or stopped: unchecked (without toggled()); `briefly` beside the
  // box, `why` on hovering.
  void failed(const QString& why, const QString& briefly = {});
  // `text` beside the box, `tip` on hovering; an empty text clears what is there unless it says a
  // failure (which stays until the next try).
  void showStatus(const QString& text, const QString& tip = {});

 signals:
  void toggled();  // checked or unchecked

 private:
  QString setting_;
  QCheckBox* box_;
  QLineEdit* target_;
  QLabel* status_;
};

}  // namespace lumistage
