#pragma once

// The picture the live-feed tests send: four flat quadrants of known colours (RGBA), so that what
// a receiver decodes can be checked at each quadrant's middle.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace lumistage::testing {

constexpr int kQuadrantsWidth = 320, kQuadrantsHeight = 240;
constexpr uint8_t kQuadrantColours[4][3] = {
    {200, 40, 40}, {40, 190, 60}, {50, 60, 210}, {220, 210, 70}};

inline std::vector<uint8_t> quadrants() {
  constexpr int w = kQuadrantsWidth, h = kQuadrantsHeight;
  std::vector<uint8_t> rgba(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t* c = kQuadrantColours[(y >= h / 2) * 2 + (x >= w / 2)];
      uint8_t* p = &rgba[(size_t(y) * w + x) * 4];
      p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
    }
  }
  return rgba;
}

}  // namespace lumistage::testing
