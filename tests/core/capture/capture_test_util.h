#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/capture/image.h"
#include "core/capture/session_writer.h"
#include "core/geometry/ring_rig.h"

namespace lumistage::test {

namespace fs = std::filesystem;

// Three 64x48 cameras: small enough that a session is written and read in milliseconds.
inline Rig smallRig(int cameras_per_node = 3) {
  RingRigSpec spec;
  spec.cameras = 3;
  spec.cameras_per_node = cameras_per_node;
  spec.width = 64;
  spec.height = 48;
  return makeRingRig(spec);
}

// A fresh, absent folder in the temporary directory, unique to this process.
inline fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_capture_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(folder);
  return folder;
}

// The images of frame `frame_id`, reproducible from (seed, frame_id): random pixels.
inline std::vector<Image> frameImages(const Rig& rig, PixelFormat format, int64_t frame_id,
                                      uint32_t seed = 1) {
  std::mt19937 rng(seed * 7919u + uint32_t(frame_id));
  std::vector<Image> images(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    images[c].resize(format, rig.camera(c).width(), rig.camera(c).height());
    for (uint8_t& p : images[c].pixels) p = uint8_t(rng());
  }
  return images;
}

inline std::vector<ImageView> views(const std::vector<Image>& images) {
  std::vector<ImageView> out;
  for (const Image& image : images) out.push_back(image.view());
  return out;
}

inline int64_t timestampOf(int64_t frame_id) {
  return frame_id * 33'333'333 + 17;
}

// Frames 0..count-1 written with SessionWriter.
inline void writeSession(const fs::path& folder, const Rig& rig, PixelFormat format, int count,
                         uint32_t seed = 1, ImageFiles files = ImageFiles::kPng) {
  SessionWriter writer(folder, rig, format, 30.0, "test", {}, files);
  for (int f = 0; f < count; ++f)
    writer.writeFrame(f, timestampOf(f), views(frameImages(rig, format, f, seed)));
}

inline void truncateFile(const fs::path& path, uintmax_t size) {
  fs::resize_file(path, size);
}

inline void replaceInFile(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = readFile(path);
  const size_t at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("test: '" + from + "' not in file");
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

}  // namespace lumistage::test
