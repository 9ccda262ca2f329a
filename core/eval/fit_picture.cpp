#include "core/eval/fit_picture.h"

#include <algorithm>
#include <array>

#include "core/capture/session_writer.h"
#include "core/imaging/keyer.h"

namespace lumistage {

void writeFitPicture(const std::filesystem::path& path, const std::vector<ImageView>& images,
                     const std::vector<const LowResSilhouette*>& silhouettes,
                     const std::vector<LowResSilhouette>& body) {
  const int count = int(silhouettes.size());
  if (count == 0) return;
  const int columns = std::min(count, 4), rows = (count + columns - 1) / columns;
  int tile_w = 0, tile_h = 0;
  for (const LowResSilhouette* s : silhouettes)
    tile_w = std::max(tile_w, s->width), tile_h = std::max(tile_h, s->height);
  const int gap = 4;
  Image picture;
  picture.resize(PixelFormat::kRgb8, columns * (tile_w + gap) - gap, rows * (tile_h + gap) - gap);
  std::fill(picture.pixels.begin(), picture.pixels.end(), uint8_t(24));
  for (int k = 0; k < count; ++k) {
    const LowResSilhouette& s = *silhouettes[size_t(k)];
    const bool has_body = size_t(k) < body.size() && !body[size_t(k)].bits.empty();
    const int ox = (k % columns) * (tile_w + gap), oy = (k / columns) * (tile_h + gap);
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) {
        Rgb c;
        const ImageView* image = size_t(k) < images.size() ? &images[size_t(k)] : nullptr;
        if (image && image->data)
          c = colourAt(*image, std::min(x * s.step + s.step / 2, image->width - 1),
                       std::min(y * s.step + s.step / 2, image->height - 1));
        const int grey = (c.r + c.g + c.b) / 6;  // dimmed
        const bool in_mask = s.at(x, y), in_body = has_body && body[size_t(k)].at(x, y);
        std::array<int, 3> tint = {grey, grey, grey};
        if (in_mask && in_body)
          tint = {grey / 2, 110 + grey, grey / 2};
        else if (in_mask)
          tint = {grey / 2, grey / 2, 120 + grey};
        else if (in_body)
          tint = {130 + grey, grey / 2, grey / 2};
        uint8_t* p = picture.pixels.data() + 3 * (size_t(oy + y) * picture.width + ox + x);
        for (int i = 0; i < 3; ++i) p[i] = uint8_t(std::min(tint[size_t(i)], 255));
      }
  }
  writePngAtomically(path, picture.view());
}

}  // namespace lumistage
