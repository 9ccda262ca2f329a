#pragma once

// Between our pixel formats and Aravis's (GenICam PFNC) codes. Internal to core/capture: it needs
// Aravis's headers.
#include <arv.h>

#include <optional>

#include "core/capture/image.h"

namespace lumistage {

inline ArvPixelFormat toAravis(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return ARV_PIXEL_FORMAT_MONO_8;
    case PixelFormat::kBayerRggb8:
      return ARV_PIXEL_FORMAT_BAYER_RG_8;
    case PixelFormat::kBayerGrbg8:
      return ARV_PIXEL_FORMAT_BAYER_GR_8;
    case PixelFormat::kBayerGbrg8:
      return ARV_PIXEL_FORMAT_BAYER_GB_8;
    case PixelFormat::kBayerBggr8:
      return ARV_PIXEL_FORMAT_BAYER_BG_8;
    case PixelFormat::kRgb8:
      return ARV_PIXEL_FORMAT_RGB_8_PACKED;
  }
  return ARV_PIXEL_FORMAT_MONO_8;
}

inline std::optional<PixelFormat> fromAravis(ArvPixelFormat format) {
  for (PixelFormat f : kAllPixelFormats) {
    if (toAravis(f) == format) return f;
  }
  return std::nullopt;
}

}  // namespace lumistage
