#pragma once

#include <QObject>
#include <QString>

class QProcess;
class QProgressDialog;
class QWidget;

namespace lumistage {

// The virtual studio's demo session: a short recording of the reference studio (12 cameras, the
// actor walking) that the demo's pipeline and camera panels replay, looping. Made once with
// `lumistage synth` and kept in the user's cache folder.
class DemoSession : public QObject {
  Q_OBJECT

 public:
  explicit DemoSession(QObject* parent = nullptr) : QObject(parent) {}

  // $XDG_CACHE_HOME/lumistage/demo-session-v1 (or LUMISTAGE_DEMO_SESSION when set).
  static QString folder();
  static bool exists();

  // Makes the session in the background (a long action: progress in a dialog over `parent`,
  // which can cancel it). Ends with made(folder) or failed(error in words); "cancelled" when the
  // user cancelled.
  void make(QWidget* parent, int frames = 60);
  void cancel();
  bool busy() const { return process_ != nullptr; }

 signals:
  void progress(int done, int total);
  void made(QString folder);
  void failed(QString error);

 private:
  void finish(int exit_code);

  QProcess* process_ = nullptr;
  QProgressDialog* dialog_ = nullptr;
  QString partial_, output_;
  int frames_ = 0;
  bool cancelled_ = false;
};

}  // namespace lumistage
