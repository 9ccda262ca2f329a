#include "core/pipeline/silhouettes.h"

namespace lumistage {

namespace {

// keyCell on a Bayer image at a step of a multiple of 4, as a node keys its cameras, without
// colourAt's generality: each cell's centre (x, y) is even and at least 2 pixels inside the
// image, so the 3x3 pixels around it always lie in the cells (x/2 - 1, y/2 - 1) (one pixel of the
// window: its last column and row) to (x/2, y/2) (two pixels a side), weighted 1, 2, 2, 4 (over
// 9). Each cell decoded as colourAt decodes it, straight from the mosaic's rows: the same result
// as keyCell, 122 against 433-565 us a camera at step 4 (235 us through colourAt).
void bayerSilhouette(const GreenScreenKeyer& key, const ImageView& image, int step,
                     LowResSilhouette& out) {
  const BayerLayout l = bayerLayout(image.format);
  const size_t w = size_t(image.width);
  for (int cy = 0; cy < out.height; ++cy) {
    const int y = cy * step + step / 2;
    // The red and the blue pixel rows of the window's two cell rows (starting at y - 2 and y).
    const uint8_t* red[2] = {image.data + (size_t(y - 2) + l.red_y) * w,
                             image.data + (size_t(y) + l.red_y) * w};
    const uint8_t* blue[2] = {image.data + (size_t(y - 1) - l.red_y) * w,
                              image.data + (size_t(y + 1) - l.red_y) * w};
    for (int cx = 0; cx < out.width; ++cx) {
      const int x = cx * step + step / 2;
      int r = 0, g = 0, b = 0;
      for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
          const int weight = (1 + i) * (1 + j);
          const size_t c = size_t(x - 2 + 2 * i);  // the cell's first pixel column
          r += weight * red[j][c + l.red_x];
          b += weight * blue[j][c + 1 - l.red_x];
          g += weight * ((red[j][c + 1 - l.red_x] + blue[j][c + l.red_x] + 1) / 2);
        }
      }
      if (key.isForeground(Rgb{(r + 4) / 9, (g + 4) / 9, (b + 4) / 9}, x, y)) out.set(cx, cy);
    }
  }
}

}  // namespace

void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out) {
  out.camera = camera;
  out.step = step;
  out.width = image.width / step;
  out.height = image.height / step;
  out.bits.assign((size_t(out.width) * out.height + 7) / 8, 0);
  if (isBayer(image.format) && step % 4 == 0 && image.width % 2 == 0 && image.height % 2 == 0) {
    bayerSilhouette(key, image, step, out);
    return;
  }
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      if (keyCell(key, image, x, y, step)) out.set(x, y);
    }
  }
}

void silhouetteMask(const LowResSilhouette& s, std::vector<uint8_t>& out) {
  const size_t cells = size_t(s.width) * s.height;
  out.resize(cells);
  for (size_t i = 0; i < cells; ++i) out[i] = uint8_t(0u - ((s.bits[i >> 3] >> (i & 7)) & 1u));
}

}  // namespace lumistage
