#pragma once

#include <optional>
#include <string>

#include "core/capture/image.h"

namespace lumistage {

// How a session's camera images are stored (session.yaml: image_files). PNG is compact and what
// the virtual studio writes. PNM (binary PGM for mono8 and Bayer, PPM for rgb8: a short header,
// then the pixels as they are) costs no CPU to write or read: what live recording uses, since a
// node's three 1024x768 Bayer images take 20 to 30 ms to encode as PNG (noisy sensor data leaves
// PNG little to find) and are only 40% larger as PNM.
enum class ImageFiles { kPng, kPnm };

// "png", "pnm": session.yaml's word for them.
inline const char* imageFilesName(ImageFiles files) {
  return files == ImageFiles::kPnm ? "pnm" : "png";
}
inline std::optional<ImageFiles> parseImageFiles(const std::string& name) {
  if (name == "png") return ImageFiles::kPng;
  if (name == "pnm") return ImageFiles::kPnm;
  return std::nullopt;
}
// A camera image's file name extension: png, pgm (one byte a pixel) or ppm (rgb8).
inline const char* imageFileExtension(ImageFiles files, PixelFormat format) {
  if (files == ImageFiles::kPng) return "png";
  return format == PixelFormat::kRgb8 ? "ppm" : "pgm";
}

}  // namespace lumistage
