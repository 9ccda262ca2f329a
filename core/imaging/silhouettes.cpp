#include "core/imaging/silhouettes.h"

#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace lumistage {

namespace {

#if defined(__SSE2__)
// bayerSilhouette's first cells of row cy at a step of 4, eight at a time: each cell's 3x3 window
// then lies in the 2x2 Bayer cells of the pixels (4cx .. 4cx + 3, 4cy .. 4cy + 3), so 32 bytes of
// each of the 4 rows hold 8 cells. 16-bit lanes hold one pixel column of a Bayer cell;
// _mm_madd_epi16 weighs a cell's two columns 1 and 2; the division by 9 is a multiplication by 7282
// / 65536, exact for every sum up to 255 · 9 + 4. Returns the cells done (a multiple of 8);
// bayerSilhouette does the rest. A 1024x768 camera: 40-48 against 203-210 us in bayerSilhouette's
// loop (`imaging_bench
// --benchmark_filter=nodeSilhouette/4`, a machine slower than the figures below).
int bayerSilhouetteRow4(const GreenScreenKeyer& key, const ImageView& image, const BayerLayout& l,
                        int cy, LowResSilhouette& out) {
  const size_t w = size_t(image.width);
  const uint8_t* rows = image.data + size_t(4 * cy) * w;
  // The window's red rows (its first and second cell rows) and its blue rows.
  const uint8_t* red[2] = {rows + l.red_y * w, rows + (2 + l.red_y) * w};
  const uint8_t* blue[2] = {rows + (1 - l.red_y) * w, rows + (3 - l.red_y) * w};
  const __m128i low = _mm_set1_epi16(0x00ff), columns = _mm_set_epi16(2, 1, 2, 1, 2, 1, 2, 1);
  const __m128i four = _mm_set1_epi16(4), ninth = _mm_set1_epi16(7282);
  // A green excess lies in -255 .. 255: any threshold beyond keys alike clamped to 16 bits.
  const __m128i threshold = _mm_set1_epi16(int16_t(std::clamp(key.threshold(), -256, 256)));
  // The channels' weighted sums of 4 cells (16 pixel columns from x), in 32-bit lanes.
  const auto sums4 = [&](size_t x) {
    __m128i r = _mm_setzero_si128(), g = r, b = r;
    for (int j = 0; j < 2; ++j) {
      const __m128i rr = _mm_loadu_si128(reinterpret_cast<const __m128i*>(red[j] + x));
      const __m128i bb = _mm_loadu_si128(reinterpret_cast<const __m128i*>(blue[j] + x));
      const __m128i r_even = _mm_and_si128(rr, low), r_odd = _mm_srli_epi16(rr, 8);
      const __m128i b_even = _mm_and_si128(bb, low), b_odd = _mm_srli_epi16(bb, 8);
      const __m128i rc = l.red_x == 0 ? r_even : r_odd, bc = l.red_x == 0 ? b_odd : b_even;
      const __m128i gc =
          _mm_avg_epu16(l.red_x == 0 ? r_odd : r_even, l.red_x == 0 ? b_even : b_odd);
      // The second cell row weighs twice the first.
      r = _mm_add_epi16(r, j == 0 ? rc : _mm_slli_epi16(rc, 1));
      g = _mm_add_epi16(g, j == 0 ? gc : _mm_slli_epi16(gc, 1));
      b = _mm_add_epi16(b, j == 0 ? bc : _mm_slli_epi16(bc, 1));
    }
    struct {
      __m128i r, g, b;
    } s{_mm_madd_epi16(r, columns), _mm_madd_epi16(g, columns), _mm_madd_epi16(b, columns)};
    return s;
  };
  const auto mean = [&](__m128i lo, __m128i hi) {
    return _mm_mulhi_epu16(_mm_add_epi16(_mm_packs_epi32(lo, hi), four), ninth);
  };
  const size_t first_bit = size_t(cy) * out.width;
  int cx = 0;
  for (; 4 * (cx + 8) <= image.width && cx + 8 <= out.width; cx += 8) {
    const auto a = sums4(size_t(4 * cx)), c = sums4(size_t(4 * cx + 16));
    const __m128i r = mean(a.r, c.r), g = mean(a.g, c.g), b = mean(a.b, c.b);
    const __m128i excess = _mm_sub_epi16(g, _mm_max_epi16(r, b));
    const __m128i actor = _mm_cmplt_epi16(excess, threshold);
    const unsigned bits = unsigned(_mm_movemask_epi8(_mm_packs_epi16(actor, actor))) & 0xffu;
    const size_t i = first_bit + size_t(cx);
    if (i % 8 == 0) {
      out.bits[i / 8] = uint8_t(bits);
    } else {
      for (int k = 0; k < 8; ++k)
        if (bits >> k & 1u) out.set(cx + k, cy);
    }
  }
  return cx;
}
#endif

// keyCell on a Bayer image at a step of a multiple of 4, as a node keys its cameras, without
// colourAt's generality: each cell's centre (x, y) is even and at least 2 pixels inside the
// image, so the 3x3 pixels around it always lie in the cells (x/2 - 1, y/2 - 1) (one pixel of the
// window: its last column and row) to (x/2, y/2) (two pixels a side), weighted 1, 2, 2, 4 (over
// 9). Each cell decoded as colourAt decodes it, straight from the mosaic's rows: the same result
// as keyCell, 122 against 433-565 us a camera at step 4 (235 us through colourAt). At step 4 it
// keys only the cells bayerSilhouetteRow4 leaves (none at 1024 pixels wide).
void bayerSilhouette(const GreenScreenKeyer& key, const ImageView& image, int step,
                     LowResSilhouette& out) {
  const BayerLayout l = bayerLayout(image.format);
  const size_t w = size_t(image.width);
  for (int cy = 0; cy < out.height; ++cy) {
    int first = 0;
#if defined(__SSE2__)
    if (step == 4) first = bayerSilhouetteRow4(key, image, l, cy, out);
#endif
    const int y = cy * step + step / 2;
    // The red and the blue pixel rows of the window's two cell rows (starting at y - 2 and y).
    const uint8_t* red[2] = {image.data + (size_t(y - 2) + l.red_y) * w,
                             image.data + (size_t(y) + l.red_y) * w};
    const uint8_t* blue[2] = {image.data + (size_t(y - 1) - l.red_y) * w,
                              image.data + (size_t(y + 1) - l.red_y) * w};
    for (int cx = first; cx < out.width; ++cx) {
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

// keyCell on an RGB image at a step of 3 or more, where every cell's 3x3 window lies inside the
// image: the window's three rows summed straight from the image, without meanColourAround's
// bounds and colourAt's format per pixel (a quarter of a node's CPU on an RGB session, 24.8% in
// perf, before). The same result as keyCell.
void rgbSilhouette(const GreenScreenKeyer& key, const ImageView& image, int step,
                   LowResSilhouette& out) {
  const size_t row_bytes = 3 * size_t(image.width);
  for (int cy = 0; cy < out.height; ++cy) {
    const int y = cy * step + step / 2;
    const uint8_t* above = image.data + size_t(y - 1) * row_bytes;
    const uint8_t* middle = above + row_bytes;
    const uint8_t* below = middle + row_bytes;
    for (int cx = 0; cx < out.width; ++cx) {
      const int x = cx * step + step / 2;
      const size_t first = 3 * size_t(x - 1);
      int sum[3] = {0, 0, 0};
      for (size_t i = first; i < first + 9; i += 3) {
        for (int c = 0; c < 3; ++c) sum[c] += above[i + c] + middle[i + c] + below[i + c];
      }
      if (key.isForeground(Rgb{(sum[0] + 4) / 9, (sum[1] + 4) / 9, (sum[2] + 4) / 9}, x, y))
        out.set(cx, cy);
    }
  }
}

}  // namespace

void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out) {
  out.reset(camera, step, image.width, image.height);
  if (isBayer(image.format) && step % 4 == 0 && image.width % 2 == 0 && image.height % 2 == 0) {
    bayerSilhouette(key, image, step, out);
    return;
  }
  if (image.format == PixelFormat::kRgb8 && step >= 3) {
    rgbSilhouette(key, image, step, out);
    return;
  }
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      if (keyCell(key, image, x, y, step)) out.set(x, y);
    }
  }
}

void computeSilhouette(const BackgroundModel& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out) {
  out.reset(camera, step, image.width, image.height);
  CellBox box;
  for (int cy = 0; cy < out.height; ++cy) {
    const int y = cy * step + step / 2;
    for (int cx = 0; cx < out.width; ++cx) {
      const int x = cx * step + step / 2;
      if (!key.isForeground(image, x, y)) continue;
      out.set(cx, cy);
      box.add(cx, cy);
    }
  }
  fillHoles(out, box);
}

void fillHoles(LowResSilhouette& silhouette) {
  CellBox box;
  for (int y = 0; y < silhouette.height; ++y)
    for (int x = 0; x < silhouette.width; ++x)
      if (silhouette.at(x, y)) box.add(x, y);
  fillHoles(silhouette, box);
}

void fillHoles(LowResSilhouette& silhouette, const CellBox& box) {
  // Only the box around the silhouette can hold a hole: every cell beyond it is background
  // joined to the border, and so is every background cell on the box's edge.
  const int x0 = box.x0, y0 = box.y0, x1 = box.x1, y1 = box.y1;
  if (x1 - x0 < 2 || y1 - y0 < 2) return;  // too small to enclose a cell
  const int bw = x1 - x0 + 1, bh = y1 - y0 + 1;
  // Per cell of the box: 1 the actor, 2 background reached from the box's edge, 0 not (yet).
  thread_local std::vector<uint8_t> state;
  thread_local std::vector<int> stack;
  state.assign(size_t(bw) * bh, 0);
  stack.clear();
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x)
      if (silhouette.at(x0 + x, y0 + y)) state[size_t(y) * bw + x] = 1;
  const auto push = [&](int x, int y) {
    uint8_t& s = state[size_t(y) * bw + x];
    if (s != 0) return;
    s = 2;
    stack.push_back(y * bw + x);
  };
  for (int x = 0; x < bw; ++x) push(x, 0), push(x, bh - 1);
  for (int y = 0; y < bh; ++y) push(0, y), push(bw - 1, y);
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    const int x = i % bw, y = i / bw;
    if (x > 0) push(x - 1, y);
    if (x + 1 < bw) push(x + 1, y);
    if (y > 0) push(x, y - 1);
    if (y + 1 < bh) push(x, y + 1);
  }
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x)
      if (state[size_t(y) * bw + x] == 0) silhouette.set(x0 + x, y0 + y);
}

void maskSilhouette(const uint8_t* mask, int width, int height, int camera, int step,
                    LowResSilhouette& out) {
  out.reset(camera, step, width, height);
  for (int y = 0; y < out.height; ++y) {
    const uint8_t* row = mask + size_t(y * step + step / 2) * width;
    for (int x = 0; x < out.width; ++x)
      if (row[x * step + step / 2]) out.set(x, y);
  }
}

void silhouetteMask(const LowResSilhouette& s, std::vector<uint8_t>& out) {
  const size_t cells = size_t(s.width) * s.height;
  out.resize(cells);
  for (size_t i = 0; i < cells; ++i) out[i] = uint8_t(0u - ((s.bits[i >> 3] >> (i & 7)) & 1u));
}

}  // namespace lumistage
