#include "core/calib/wand_detector.h"

#include <algorithm>

namespace lumistage {

WandDetection WandDetector::detect(const ImageView& image) {
  WandDetection out;
  bright_.clear();
  const int channels = image.format == PixelFormat::kRgb8 ? 3 : 1;
  const int threshold = options_.threshold;
  for (int y = 0; y < image.height; ++y) {
    const uint8_t* row = image.data + static_cast<size_t>(y) * image.width * channels;
    for (int x = 0; x < image.width; ++x) {
      int v = row[x * channels];
      if (channels == 3) v = std::max({v, int(row[x * 3 + 1]), int(row[x * 3 + 2])});
      if (v <= threshold) continue;
      if (static_cast<int>(bright_.size()) >= options_.max_pixels) {
        out.status = WandDetection::Status::kTooBright;
        return out;
      }
      bright_.push_back({x, y, v - threshold});
    }
  }
  if (bright_.empty()) return out;
  // Blobs: 8-connected components of the bright pixels, found by a flood fill over the list
  // (sorted by row, then column, as scanned), looking neighbours up by binary search.
  const int n = static_cast<int>(bright_.size());
  label_.assign(n, -1);
  auto find = [&](int x, int y) {
    const auto it = std::lower_bound(
        bright_.begin(), bright_.end(), Bright{x, y, 0},
        [](const Bright& a, const Bright& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
    return it != bright_.end() && it->x == x && it->y == y ? static_cast<int>(it - bright_.begin())
                                                           : -1;
  };
  int best_pixels = 0;
  double best_x = 0, best_y = 0;
  for (int i = 0; i < n; ++i) {
    if (label_[i] >= 0) continue;
    label_[i] = i;
    stack_.assign(1, i);
    int pixels = 0;
    double sw = 0, sx = 0, sy = 0;
    while (!stack_.empty()) {
      const int j = stack_.back();
      stack_.pop_back();
      const Bright& b = bright_[j];
      ++pixels;
      sw += b.weight, sx += double(b.weight) * b.x, sy += double(b.weight) * b.y;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int k = find(b.x + dx, b.y + dy);
          if (k >= 0 && label_[k] < 0) {
            label_[k] = i;
            stack_.push_back(k);
          }
        }
      }
    }
    if (pixels < options_.min_pixels) continue;
    ++out.blobs;
    if (pixels > best_pixels) best_pixels = pixels, best_x = sx / sw, best_y = sy / sw;
  }
  if (out.blobs == 0) return out;
  out.pixels = best_pixels;
  out.pixel = {best_x, best_y};
  out.status = out.blobs == 1 ? WandDetection::Status::kFound : WandDetection::Status::kAmbiguous;
  return out;
}

}  // namespace lumistage
