#pragma once

#include <QString>
#include <QWidget>
#include <optional>
#include <string>

#include "core/base/error.h"

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
  // While the box is checked, its target parsed by `parse` (which throws Error for a text that is
  // none) and remembered for the next session; none otherwise, or when the text is no target: then
  // unchecked, `expected` beside the box and the parser's words on hovering.
  template <typename Parse>
  auto wantedTarget(Parse parse, const QString& expected)
      -> std::optional<decltype(parse(std::string()))> {
    const QString text = checkedTarget();
    if (text.isEmpty()) return std::nullopt;
    try {
      auto target = parse(text.toStdString());
      rememberTarget();
      return target;
    } catch (const Error& e) {
      failed(QString::fromStdString(e.what()), expected);
      return std::nullopt;
    }
  }
  // The output could not start or stopped: unchecked (without toggled()); `briefly` beside the
  // box, `why` on hovering.
  void failed(const QString& why, const QString& briefly = {});
  // `text` beside the box, `tip` on hovering; an empty text clears what is there unless it says a
  // failure (which stays until the next try).
  void showStatus(const QString& text, const QString& tip = {});

 signals:
  void toggled();  // checked or unchecked

 private:
  QString checkedTarget() const;  // trimmed while the box is checked; empty otherwise
  void rememberTarget() const;
  QString setting_;
  QCheckBox* box_;
  QLineEdit* target_;
  QLabel* status_;
};

}  // namespace lumistage
