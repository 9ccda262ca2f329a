#include "core/capture/session_writer.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/mesh_sequence_io.h"
#include "core/geometry/rig_file.h"

namespace lumistage {

namespace fs = std::filesystem;

size_t writePngAtomically(const fs::path& path, const ImageView& view) {
  const cv::Mat source(view.height, view.width,
                       view.format == PixelFormat::kRgb8 ? CV_8UC3 : CV_8UC1,
                       const_cast<uint8_t*>(view.data));
  cv::Mat image = source;
  if (view.format == PixelFormat::kRgb8)
    cv::cvtColor(source, image, cv::COLOR_RGB2BGR);  // imencode takes BGR
  // Fast PNG: the session is written while capturing (lossless at any level). Run-length
  // matching instead of zlib's default search: a 1024x768 Bayer frame of the virtual studio in
  // 11.7 against 17.7 ms (its sensor noise leaves few matches to find; 20% more bytes), an RGB
  // frame in 40 against 47 ms and 17% fewer bytes, a truth mask in a third of the bytes.
  const std::vector<int> options = {cv::IMWRITE_PNG_COMPRESSION, 1, cv::IMWRITE_PNG_STRATEGY,
                                    cv::IMWRITE_PNG_STRATEGY_RLE};
  thread_local std::vector<uchar> encoded;  // reused: no allocation per image once warmed up
  try {
    if (!cv::imencode(".png", image, encoded, options))
      throw Error(path.string() + ": cannot encode the image as PNG");
  } catch (const cv::Exception& e) {
    throw Error(path.string() + ": cannot encode image: " + e.err);
  }
  writeFileAtomically(
      path, std::string_view(reinterpret_cast<const char*>(encoded.data()), encoded.size()),
      {.sync = false});
  return encoded.size();
}

namespace {

// A camera's truth mask (one byte a pixel) as an image.
ImageView maskView(const Camera& camera, const std::vector<uint8_t>& mask) {
  return {PixelFormat::kMono8, camera.width(), camera.height(), mask.data()};
}

// A PNM file (binary PGM or PPM, maxval 255): the header, then the rows as they are.
size_t writePnmAtomically(const fs::path& path, const ImageView& view) {
  const std::string header = fmt::format(
      "{}\n{} {}\n255\n", view.format == PixelFormat::kRgb8 ? "P6" : "P5", view.width, view.height);
  const std::string_view pixels(reinterpret_cast<const char*>(view.data), view.bytes());
  writeFileAtomically(path, {header, pixels}, {.sync = false});
  return header.size() + pixels.size();
}

}  // namespace

SessionWriter::SessionWriter(const fs::path& folder, const Rig& rig, PixelFormat format, double fps,
                             const std::string& source, const std::vector<std::string>& joint_names,
                             ImageFiles files)
    : folder_(folder), rig_(rig), format_(format), files_(files), joint_names_(joint_names) {
  std::error_code ec;
  if (fs::exists(folder_, ec) && !fs::is_empty(folder_, ec)) {
    throw Error(folder_.string() +
                ": already exists and is not empty; a session is never written over another");
  }
  fs::create_directories(folder_, ec);
  if (ec) throw Error(folder_.string() + ": cannot create: " + ec.message());
  const bool truth = !joint_names_.empty();
  for (const Camera& camera : rig_.cameras()) {
    fs::create_directories(folder_ / camera.name(), ec);
    if (truth) fs::create_directories(folder_ / "truth" / "masks" / camera.name(), ec);
    if (ec) throw Error(folder_.string() + ": cannot create camera folders: " + ec.message());
  }
  if (truth) fs::create_directories(folder_ / "truth" / "surface", ec);
  saveRig(rig_, folder_ / "rig.yaml");
  std::string cameras;
  for (const Camera& c : rig_.cameras()) cameras += (cameras.empty() ? "" : ", ") + c.name();
  writeFileAtomically(
      folder_ / "session.yaml",
      fmt::format("# Lumistage recorded session: see docs/session-format.md.\n"
                  "format: lumistage-session\nversion: 1\nsource: {}\nrig: rig.yaml\n"
                  "fps: {}\npixel_format: {}\nimage_files: {}\ncameras: [{}]\n"
                  "truth: {}\n",
                  source, fps, pixelFormatName(format_), imageFilesName(files_), cameras,
                  truth ? "true" : "false"));
  index_.create(folder_ / "index.csv");
  if (!index_.append("frame,timestamp_ns\n"))
    throw Error(index_.path().string() + ": cannot write: " + index_.status().error());
  if (truth) {
    joints_.create(folder_ / "truth" / "joints.csv");
    std::string header = "frame";
    for (const std::string& name : joint_names_) header += fmt::format(",{0}_x,{0}_y,{0}_z", name);
    if (!joints_.append(header + "\n"))
      throw Error(joints_.path().string() + ": cannot write: " + joints_.status().error());
  }
}

SessionWriter::~SessionWriter() = default;

void SessionWriter::writeFrame(int64_t frame_id, int64_t timestamp_ns,
                               const std::vector<ImageView>& images, const FrameTruth* truth) {
  checkImages(fmt::format("frame {}", frame_id), images);
  const std::string name = fmt::format("{:06}.{}", frame_id, imageFileExtension(files_, format_));
  const std::string mask_name = fmt::format("{:06}.png", frame_id);
  // PNG encoding dominates a frame's writing: cameras in parallel, errors carried out.
  std::vector<std::string> errors(rig_.cameraCount());
  std::atomic<int64_t> bytes = 0;
  cv::parallel_for_(cv::Range(0, rig_.cameraCount()), [&](const cv::Range& range) {
    for (int c = range.start; c < range.end; ++c) {
      try {
        const Camera& camera = rig_.camera(c);
        const ImageView& view = images[c];
        bytes += int64_t(writeImage(folder_ / camera.name() / name, view));
        if (truth && truth->masks) {
          writePngAtomically(folder_ / "truth" / "masks" / camera.name() / mask_name,
                             maskView(camera, (*truth->masks)[c]));
        }
      } catch (const std::exception& e) {
        errors[c] = e.what();
      }
    }
  });
  for (const std::string& error : errors) {
    if (!error.empty()) throw Error(error);
  }
  if (truth) writeTruth(frame_id, *truth, false);  // its masks beside the images, above
  appendIndex(frame_id, timestamp_ns, bytes);
}

void SessionWriter::checkImages(const std::string& what,
                                const std::vector<ImageView>& images) const {
  if (images.size() != static_cast<size_t>(rig_.cameraCount())) {
    throw Error(fmt::format("{}: {} has {} images for {} cameras", folder_.string(), what,
                            images.size(), rig_.cameraCount()));
  }
  for (int c = 0; c < rig_.cameraCount(); ++c) {
    const Camera& camera = rig_.camera(c);
    const ImageView& view = images[c];
    if (view.format != format_ || view.width != camera.width() || view.height != camera.height() ||
        !view.data) {
      throw Error(fmt::format("{}: {}, camera {}: got a {}x{} {} image, the session holds {}x{} {}",
                              folder_.string(), what, camera.name(), view.width, view.height,
                              pixelFormatName(view.format), camera.width(), camera.height(),
                              pixelFormatName(format_)));
    }
  }
}

size_t SessionWriter::writeImage(const fs::path& path, const ImageView& view) const {
  return files_ == ImageFiles::kPnm ? writePnmAtomically(path, view)
                                    : writePngAtomically(path, view);
}

void SessionWriter::writePlate(int index, const std::vector<ImageView>& images) {
  checkImages(fmt::format("plate frame {}", index), images);
  const std::string name = fmt::format("{:06}.{}", index, imageFileExtension(files_, format_));
  for (int c = 0; c < rig_.cameraCount(); ++c) {
    const fs::path folder = folder_ / "plate" / rig_.camera(c).name();
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw Error(folder.string() + ": cannot create the plate's folder: " + ec.message());
    writeImage(folder / name, images[c]);
  }
}

void SessionWriter::writeTruth(int64_t frame_id, const FrameTruth& truth, bool masks) {
  if (joints_.path().empty())
    throw Error(fmt::format("{}: frame {}: truth for a session made without it", folder_.string(),
                            frame_id));
  if (masks && truth.masks) {
    for (int c = 0; c < rig_.cameraCount(); ++c) {
      const Camera& camera = rig_.camera(c);
      writePngAtomically(
          folder_ / "truth" / "masks" / camera.name() / fmt::format("{:06}.png", frame_id),
          maskView(camera, (*truth.masks)[c]));
    }
  }
  if (truth.surface)
    saveMeshPly(folder_ / "truth" / "surface" / fmt::format("{:06}.ply", frame_id), *truth.surface);
  std::string line = std::to_string(frame_id);
  for (const Eigen::Vector3d& j : truth.joints)
    line += fmt::format(",{},{},{}", j.x(), j.y(), j.z());
  line += "\n";
  if (!joints_.append(line))
    throw Error(fmt::format("{}: cannot append frame {}: {}; the session ends before it",
                            joints_.path().string(), frame_id, joints_.status().error()));
}

void SessionWriter::copyFrame(int64_t frame_id, int64_t timestamp_ns,
                              const std::vector<fs::path>& files, const FrameTruth* truth) {
  if (files.size() != static_cast<size_t>(rig_.cameraCount())) {
    throw Error(fmt::format("{}: frame {} has {} images for {} cameras", folder_.string(), frame_id,
                            files.size(), rig_.cameraCount()));
  }
  const std::string name = fmt::format("{:06}.{}", frame_id, imageFileExtension(files_, format_));
  int64_t bytes = 0;
  for (int c = 0; c < rig_.cameraCount(); ++c) {
    const std::string contents = readFile(files[c]);
    writeFileAtomically(folder_ / rig_.camera(c).name() / name, contents, {.sync = false});
    bytes += static_cast<int64_t>(contents.size());
  }
  if (truth) writeTruth(frame_id, *truth, true);
  appendIndex(frame_id, timestamp_ns, bytes);
}

void SessionWriter::appendIndex(int64_t frame_id, int64_t timestamp_ns, int64_t bytes) {
  char line[48];
  const auto end = fmt::format_to_n(line, sizeof line, "{},{}\n", frame_id, timestamp_ns).out;
  if (!index_.append(std::string_view(line, size_t(end - line))))
    throw Error(fmt::format("{}: cannot append frame {}: {}; the session ends before it",
                            index_.path().string(), frame_id, index_.status().error()));
  ++frames_;
  bytes_ += bytes;
}

}  // namespace lumistage
