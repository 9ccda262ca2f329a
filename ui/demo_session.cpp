#include "ui/demo_session.h"

#include <QCoreApplication>
#include <QDir>
#include <QFileInfo>
#include <QProcess>
#include <QProgressDialog>
#include <QRegularExpression>
#include <QStandardPaths>
#include <exception>

#include "core/base/resource_path.h"

namespace lumistage {

QString DemoSession::folder() {
  const QString override_folder = qEnvironmentVariable("LUMISTAGE_DEMO_SESSION");
  if (!override_folder.isEmpty()) return override_folder;
  return QStandardPaths::writableLocation(QStandardPaths::GenericCacheLocation) +
         "/lumistage/demo-session-v1";
}

bool DemoSession::exists() {
  return QFileInfo::exists(folder() + "/rig.yaml") && QFileInfo::exists(folder() + "/.complete");
}

void DemoSession::make(QWidget* parent, int frames) {
  if (process_) return;
  const QString cli = QCoreApplication::applicationDirPath() + "/lumistage";
  QString config;
  try {
    config = QString::fromStdString(resourcePath("studio/reference.yaml").string());
  } catch (const std::exception& e) {
    emit failed(QString::fromStdString(e.what()));
    return;
  }
  if (!QFileInfo::exists(cli)) {
    emit failed(tr("cannot make the demo session: no %1 (build the lumistage target)").arg(cli));
    return;
  }
  frames_ = frames;
  cancelled_ = false;
  QDir(folder()).removeRecursively();
  partial_ = folder() + ".partial";
  QDir(partial_).removeRecursively();
  QDir().mkpath(QFileInfo(partial_).absolutePath());
  output_.clear();
  process_ = new QProcess(this);
  process_->setProcessChannelMode(QProcess::MergedChannels);
  dialog_ = new QProgressDialog(tr("Filming the virtual studio for the demo (once)..."),
                                tr("Cancel"), 0, frames, parent);
  dialog_->setWindowModality(Qt::WindowModal);
  dialog_->setMinimumDuration(0);
  dialog_->setValue(0);
  connect(dialog_, &QProgressDialog::canceled, this, &DemoSession::cancel);
  connect(process_, &QProcess::readyRead, this, [this] {
    output_ += QString::fromUtf8(process_->readAll());
    // "synth: 12/60, ..." a line per tenth (or "synth [###...] 12/60" on a terminal).
    static const QRegularExpression done_re("synth.*?(\\d+)/(\\d+)");
    QRegularExpressionMatchIterator it = done_re.globalMatch(output_);
    int done = -1;
    while (it.hasNext()) done = it.next().captured(1).toInt();
    if (done >= 0) {
      if (dialog_) dialog_->setValue(std::min(done, frames_ - 1));
      emit progress(done, frames_);
    }
    if (output_.size() > 20000) output_ = output_.right(4000);
  });
  connect(process_, &QProcess::finished, this,
          [this](int code, QProcess::ExitStatus) { finish(code); });
  connect(process_, &QProcess::errorOccurred, this, [this](QProcess::ProcessError error) {
    if (error == QProcess::FailedToStart) finish(-1);
  });
  process_->start(
      cli, {"synth", "--config", config, "--frames", QString::number(frames), "--out", partial_});
}

void DemoSession::cancel() {
  if (!process_) return;
  cancelled_ = true;
  process_->kill();  // finish() follows
}

void DemoSession::finish(int exit_code) {
  if (!process_) return;
  process_->deleteLater();
  process_ = nullptr;
  if (dialog_) {
    dialog_->disconnect(this);
    dialog_->close();
    dialog_->deleteLater();
    dialog_ = nullptr;
  }
  if (cancelled_) {
    QDir(partial_).removeRecursively();
    emit failed(tr("cancelled"));
    return;
  }
  if (exit_code != 0) {
    QDir(partial_).removeRecursively();
    const QString last = output_.trimmed().section('\n', -3);
    emit failed(tr("lumistage synth failed (status %1): %2").arg(exit_code).arg(last));
    return;
  }
  QFile marker(partial_ + "/.complete");
  if (!marker.open(QIODevice::WriteOnly) || !QDir().rename(partial_, folder())) {
    emit failed(tr("cannot move the demo session into %1").arg(folder()));
    return;
  }
  emit made(folder());
}

}  // namespace lumistage
