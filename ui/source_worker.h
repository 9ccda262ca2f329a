#pragma once

#include <QImage>
#include <QObject>
#include <QString>
#include <QVector>
#include <atomic>
#include <memory>

#include "core/capture/frame_source.h"
#include "core/imaging/keyer.h"

namespace lumistage {

// Where the studio's frames come from.
struct SourceSpec {
  enum class Kind { kVirtualStudio, kSession, kAravis };
  Kind kind = Kind::kVirtualStudio;
  QString path;              // studio config (virtual studio) or session folder
  QString rig;               // rig file (Aravis)
  QString address;           // first camera's address (Aravis): camera i at address + i
  bool from_memory = false;  // a session decoded up front (then nothing but previews to make)

  // "virtual", "virtual:CONFIG", "session:DIR", "aravis:ADDRESS"; empty string on success, else
  // what is wrong.
  static QString parse(const QString& text, SourceSpec& out);
  QString describe() const;
};

// What the camera panel shows of one camera.
struct CameraStatus {
  double frame_rate_hz = 0;
  qint64 frames = 0;
  qint64 dropped = 0;
  QString last_error;
};

// Runs a FrameSource on its own thread (move it to a QThread, then call run()): opens the source
// there (the virtual studio's OpenGL context lives on that thread), pulls frames, and emits small
// previews of each camera at a few per second, plus the cameras' counters once a second.
class SourceWorker : public QObject {
  Q_OBJECT

 public:
  explicit SourceWorker(SourceSpec spec) : spec_(std::move(spec)) {}
  void stop() { stop_ = true; }
  // The camera whose every frame is previewed too (watchedFrame): the skeleton overlay's, which
  // draws the body placed for one frame over that frame's picture. -1: none. Any thread.
  void watchCamera(int camera) { watched_ = camera; }

  // A quarter-size RGB preview of a camera image (Bayer: one colour per 2x2 cell, decimated).
  static QImage preview(const Image& image);
  // The actor's mask at the preview's pixels (8 bits, 255 on the actor) where the source says
  // better than the picture's green: the frame's own mask from another tool (`frame.mask`), else
  // the camera's clean plate (`plate`); null when it has neither (the picture is keyed green).
  static QImage previewMask(const CameraFrame& frame, const BackgroundModel* plate);

 public slots:
  void run();

 signals:
  void opened(std::shared_ptr<const lumistage::Rig> rig, QString description);
  void failed(QString error);
  // A few previews a second a camera (4), for every panel.
  // `mask`: previewMask (null: key the picture's green).
  void frame(int camera, QImage preview, qint64 frame_id, QImage mask);
  // Every frame of the watched camera.
  void watchedFrame(int camera, QImage preview, qint64 frame_id, QImage mask);
  void status(QVector<lumistage::CameraStatus> cameras);
  void finished();

 private:
  SourceSpec spec_;
  std::atomic<bool> stop_{false};
  std::atomic<int> watched_{-1};
};

}  // namespace lumistage

Q_DECLARE_METATYPE(std::shared_ptr<const lumistage::Rig>)
Q_DECLARE_METATYPE(lumistage::CameraStatus)
