#include "core/imaging/mask_repair.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/base/error.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_writer.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// The longest side of a picture of a repair.
constexpr int kPictureSide = 960;

// Progress over every camera's reads: the frames learnt from, then every frame.
struct Progress {
  const std::function<void(int, int)>& report;
  int done = 0, total = 0;
  void step() {
    if (report) report(++done, total);
  }
};

// Frame i's given mask of camera c, or empty (with a note) when it has none.
std::vector<uint8_t> givenMask(const SessionReader& reader, int c, int i,
                               std::vector<std::string>& notes) {
  std::error_code ec;
  const fs::path file = reader.givenMaskPath(c, i);
  if (!fs::exists(file, ec)) {
    notes.push_back(fmt::format("{}: no given mask of frame {}: it keeps none", file.string(),
                                reader.frameId(i)));
    return {};
  }
  return reader.readGivenMask(c, i);
}

ImageView maskView(const std::vector<uint8_t>& mask, const Camera& camera) {
  return {PixelFormat::kMono8, camera.width(), camera.height(), mask.data()};
}

// Camera c's plate, learnt from frames spread over the session.
TakePlate learnPlate(const SessionReader& reader, int c, const TakePlateOptions& options,
                     Progress& progress) {
  std::vector<std::string> notes;  // repairCamera() notes the frames without a mask
  const Camera& camera = reader.rig().camera(c);
  TakePlate plate(camera.name(), camera.width(), camera.height(), options);
  std::vector<CameraFrame> frames;
  for (int i : TakePlate::framesToLearn(reader.frameCount(), options.frames)) {
    const std::vector<uint8_t> given = givenMask(reader, c, i, notes);
    progress.step();
    if (given.empty()) continue;
    reader.readFrame(i, frames, {c});
    plate.add(frames[size_t(c)].image.view(), maskView(given, camera));
  }
  plate.learn();
  return plate;
}

void writePicture(const fs::path& file, const Image& picture) {
  const cv::Mat rgb(picture.height, picture.width, CV_8UC3,
                    const_cast<uint8_t*>(picture.pixels.data()));
  const double scale = std::min(1.0, double(kPictureSide) / std::max(rgb.cols, rgb.rows));
  cv::Mat small = rgb;
  if (scale < 1) cv::resize(rgb, small, {}, scale, scale, cv::INTER_AREA);
  writePngAtomically(file, {PixelFormat::kRgb8, small.cols, small.rows, small.data});
}

// Repairs camera c's masks of every frame into `out`/CAMERA/.
MaskRepairCamera repairCamera(const SessionReader& reader, int c, const fs::path& out,
                              const MaskRepairOptions& options, std::vector<std::string>& notes,
                              Progress& progress) {
  const Camera& camera = reader.rig().camera(c);
  const TakePlate plate = learnPlate(reader, c, options.plate, progress);
  MaskRepairCamera report;
  report.camera = camera.name();
  report.known = plate.knownShare();
  fs::create_directories(out / camera.name());
  std::vector<CameraFrame> frames;
  size_t given = 0, repaired = 0, added = 0, removed = 0, fallback = 0;
  for (int i = 0; i < reader.frameCount(); ++i) {
    const std::vector<uint8_t> mask = givenMask(reader, c, i, notes);
    progress.step();
    if (mask.empty()) continue;
    reader.readFrame(i, frames, {c});
    const ImageView image = frames[size_t(c)].image.view();
    const PlateRepair r = plate.repair(image, maskView(mask, camera));
    writePngAtomically(out / camera.name() / fmt::format("{:06}.png", reader.frameId(i)),
                       maskView(r.mask, camera));
    if (!options.pictures.empty() && i % std::max(1, options.picture_every) == 0)
      writePicture(options.pictures / fmt::format("{}-{:06}.png", camera.name(), reader.frameId(i)),
                   repairPicture(plate, image, maskView(mask, camera), r.mask));
    ++report.frames;
    report.changed += r.changed();
    if (r.changed() > report.most || report.most_frame < 0)
      report.most = r.changed(), report.most_frame = reader.frameId(i);
    given += r.given, repaired += r.repaired, added += r.added, removed += r.removed;
    fallback += r.fallback;
  }
  if (report.frames > 0) report.changed /= report.frames;
  report.added = given > 0 ? double(added) / double(given) : 0;
  report.removed = given > 0 ? double(removed) / double(given) : 0;
  report.fallback = repaired > 0 ? double(fallback) / double(repaired) : 0;
  return report;
}

}  // namespace

MaskRepairReport repairSessionMasks(const fs::path& session, const MaskRepairOptions& options,
                                    const std::function<void(int, int)>& progress) {
  const SessionReader reader(session);
  MaskRepairReport report;
  report.again = reader.hasRepairedMasks();
  if (!reader.hasMasks() && !report.again)
    throw Error(fmt::format("{}: the session has no masks/ to repair (session import --masks)",
                            session.string()));
  report.frames = reader.frameCount();
  const int cameras = reader.rig().cameraCount();
  Progress steps{
      progress, 0,
      cameras * (reader.frameCount() +
                 int(TakePlate::framesToLearn(reader.frameCount(), options.plate.frames).size()))};
  const fs::path partial = session / "masks.repairing";
  fs::remove_all(partial);
  if (!options.pictures.empty()) fs::create_directories(options.pictures);
  try {
    for (int c = 0; c < cameras; ++c)
      report.cameras.push_back(repairCamera(reader, c, partial, options, report.notes, steps));
  } catch (...) {
    std::error_code ec;
    fs::remove_all(partial, ec);  // the session as it was
    throw;
  }
  // Every mask is whole: the given ones kept (the first time), the repaired ones put in place.
  if (!report.again)
    fs::rename(session / "masks", session / "masks-given");
  else
    fs::remove_all(session / "masks");
  fs::rename(partial, session / "masks");
  return report;
}

std::string describeMaskRepair(const MaskRepairReport& report) {
  std::string text = fmt::format("{:<10} {:>6} {:>12}  {:>31}  {:>7} {:>8}  {}\n", "camera",
                                 "frames", "plate known", "mask changed (1 - IoU)", "added",
                                 "removed", "kept as given (plate unknown)");
  for (const MaskRepairCamera& c : report.cameras)
    text += fmt::format("{:<10} {:>6} {:>11.1f}%  {:>31}  {:>+6.1f}% {:>+7.1f}%  {:.1f}%\n",
                        c.camera, c.frames, 100 * c.known,
                        fmt::format("mean {:.1f}%, most {:.1f}% (frame {})", 100 * c.changed,
                                    100 * c.most, c.most_frame),
                        100 * c.added, -100 * c.removed, 100 * c.fallback);
  return text;
}

}  // namespace lumistage
