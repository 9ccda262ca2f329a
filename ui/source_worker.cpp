#include "ui/source_worker.h"

#include <chrono>
#include <exception>

#include "core/base/resource_path.h"
#include "core/capture/aravis_source.h"
#include "core/capture/session_source.h"
#include "core/capture/virtual_gige_cameras.h"
#include "core/geometry/rig_file.h"
#include "core/imaging/clean_plate.h"
#include "core/imaging/keyer.h"
#include "core/sim/virtual_studio_source.h"

namespace lumistage {

QString SourceSpec::parse(const QString& text, SourceSpec& out) {
  const QString kind = text.section(':', 0, 0);
  const QString rest = text.section(':', 1);
  if (kind == "virtual") {
    out.kind = Kind::kVirtualStudio;
    out.path = rest;
  } else if (kind == "session" && !rest.isEmpty()) {
    out.kind = Kind::kSession;
    out.path = rest;
  } else if (kind == "aravis") {
    out.kind = Kind::kAravis;
    out.address = rest.isEmpty() ? "127.0.1.1" : rest;
  } else {
    return QString(
               "unknown source '%1': expected virtual[:CONFIG], session:DIR or "
               "aravis[:FIRST_ADDRESS]")
        .arg(text);
  }
  return {};
}

QString SourceSpec::describe() const {
  switch (kind) {
    case Kind::kVirtualStudio:
      return "virtual studio";
    case Kind::kSession:
      return "session " + path;
    case Kind::kAravis:
      return "Aravis cameras from " + address;
  }
  return {};
}

QImage SourceWorker::preview(const Image& image) {
  const int w = image.width / 4, h = image.height / 4;
  QImage out(w, h, QImage::Format_RGB888);
  for (int y = 0; y < h; ++y) {
    uchar* row = out.scanLine(y);
    for (int x = 0; x < w; ++x) {
      const size_t sx = 4 * size_t(x), sy = 4 * size_t(y);
      const Rgb c = colourAt(image.view(), static_cast<int>(sx), static_cast<int>(sy));
      const uchar r = uchar(c.r), g = uchar(c.g), b = uchar(c.b);
      row[3 * x] = r, row[3 * x + 1] = g, row[3 * x + 2] = b;
    }
  }
  return out;
}

QImage SourceWorker::previewMask(const CameraFrame& frame, const BackgroundModel* plate) {
  const Image& image = frame.image;
  const bool masked = frame.mask.size() == size_t(image.width) * image.height;
  if (!masked && !plate) return {};
  const int w = image.width / 4, h = image.height / 4;
  QImage out(w, h, QImage::Format_Grayscale8);
  for (int y = 0; y < h; ++y) {
    uchar* row = out.scanLine(y);
    for (int x = 0; x < w; ++x) {
      const int sx = 4 * x, sy = 4 * y;
      const bool actor = masked ? frame.mask[size_t(sy) * image.width + sx] != 0
                                : plate->isForeground(image.view(), sx, sy);
      row[x] = actor ? 255 : 0;
    }
  }
  return out;
}

void SourceWorker::run() {
  using Clock = std::chrono::steady_clock;
  try {
    std::unique_ptr<FrameSource> source;
    SessionSource* session = nullptr;  // a recording: only the images previewed are copied
    QString description = spec_.describe();
    if (spec_.kind == SourceSpec::Kind::kVirtualStudio) {
      const std::string config = spec_.path.isEmpty()
                                     ? resourcePath("studio/reference.yaml").string()
                                     : spec_.path.toStdString();
      auto studio = std::make_unique<VirtualStudioSource>(loadStudioConfig(config), 300);
      description += " on " + QString::fromStdString(studio->studio().rendererDescription());
      source = std::move(studio);
    } else if (spec_.kind == SourceSpec::Kind::kSession) {
      ReplayOptions options;
      options.mode = spec_.from_memory ? ReplayMode::kFromMemory : ReplayMode::kRecordedRate;
      options.loop = true;
      // Paced by the machine's clock: the same instant, with the same frame ids, as the pipeline's
      // nodes replaying the session, so that overlays of the pipeline's body match the pictures.
      options.synchronized = true;
      options.cancel = &stop_;  // closing the window while the demo loads does not wait for it
      auto replay = std::make_unique<SessionSource>(spec_.path.toStdString(), options);
      session = replay.get();
      source = std::move(replay);
    } else {
      if (spec_.rig.isEmpty()) throw std::runtime_error("Aravis cameras need a rig file (--rig)");
      const Rig rig = loadRig(spec_.rig.toStdString());
      std::vector<AravisCameraConfig> configs(rig.cameraCount());
      for (int c = 0; c < rig.cameraCount(); ++c) {
        configs[c].device = VirtualGigeCameras::addressOf(spec_.address.toStdString(), c);
      }
      source = std::make_unique<AravisSource>(rig, configs);
    }
    const int cameras = source->rig().cameraCount();
    // The clean plates of a stage filmed empty before the take: the previews' silhouettes are
    // keyed on them, as the nodes key the frames.
    CameraPlates plates(cameras);
    for (int c = 0; c < cameras && !stop_; ++c)
      if (!source->hasMasks(c)) plates[c] = sourcePlate(*source, c);
    emit opened(std::make_shared<const Rig>(source->rig()), description);
    std::vector<Clock::time_point> last_preview(cameras);
    auto last_status = Clock::now();
    CameraFrame frame;
    // A few previews a second per camera are plenty for a person; the rest is not drawn.
    const auto due = [&](int camera) {
      return Clock::now() - last_preview[camera] > std::chrono::milliseconds(250);
    };
    while (!stop_ && !source->finished()) {
      constexpr std::chrono::milliseconds kWait(100);
      const bool wanted =
          !session || session->nextCamera() == watched_ || due(session->nextCamera());
      if (session ? session->next(frame, kWait, wanted) : source->next(frame, kWait)) {
        const bool watched = frame.camera == watched_, previewed = due(frame.camera);
        if (wanted && (watched || previewed)) {
          const QImage picture = preview(frame.image);
          const QImage mask = previewMask(frame, plates[frame.camera].get());
          if (watched) emit watchedFrame(frame.camera, picture, frame.frame_id, mask);
          if (previewed) {
            last_preview[frame.camera] = Clock::now();
            emit this->frame(frame.camera, picture, frame.frame_id, mask);
          }
        }
      }
      if (Clock::now() - last_status > std::chrono::seconds(1)) {
        last_status = Clock::now();
        QVector<CameraStatus> all(cameras);
        for (int c = 0; c < cameras; ++c) {
          const CameraStats s = source->stats(c);
          all[c] = {s.frame_rate_hz, s.frames, s.dropped, QString::fromStdString(s.last_error)};
        }
        emit status(all);
      }
    }
  } catch (const std::exception& e) {
    emit failed(QString::fromStdString(e.what()));
  }
  emit finished();
}

}  // namespace lumistage
