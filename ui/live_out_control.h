#pragma once

#include <QString>
#include <cstdint>
#include <optional>

#include "core/live/vmc_sender.h"
#include "ui/live_target_row.h"

namespace lumistage {

// The studio's live feed of the skeleton (VMC over OSC, as `lumistage run --osc`): a check box
// and the receiver's HOST:PORT, remembered between sessions (settings pipeline/osc). Checked while
// the pipeline runs, every frame shown goes out; the pipeline panel asks its worker.
class LiveOutControl : public LiveTargetRow {
  Q_OBJECT

 public:
  explicit LiveOutControl(QWidget* parent = nullptr);
  // The receiver when the box is checked and its text is HOST:PORT; none otherwise (a text that
  // is not one unchecks the box and says why beside it).
  std::optional<OscTarget> wantedTarget();
  // What the pipeline's snapshot says of the stream: its target (empty: none) and bundles sent.
  void showStream(const QString& target, int64_t bundles);
};

}  // namespace lumistage
