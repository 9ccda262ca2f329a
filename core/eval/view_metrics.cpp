#include "core/eval/view_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "core/base/error.h"
#include "core/imaging/keyer.h"
#include "core/render/silhouette_feather.h"

namespace lumistage {

namespace {

// Box sums over (2r+1)^2 windows, clamped at the borders, through an integral image.
void boxMean(const std::vector<double>& in, int w, int h, int r, std::vector<double>& out) {
  std::vector<double> integral(size_t(w + 1) * (h + 1), 0.0);
  for (int y = 0; y < h; ++y) {
    double row = 0;
    for (int x = 0; x < w; ++x) {
      row += in[size_t(y) * w + x];
      integral[size_t(y + 1) * (w + 1) + x + 1] = integral[size_t(y) * (w + 1) + x + 1] + row;
    }
  }
  out.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(0, y - r), y1 = std::min(h, y + r + 1);
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - r), x1 = std::min(w, x + r + 1);
      const double s = integral[size_t(y1) * (w + 1) + x1] - integral[size_t(y0) * (w + 1) + x1] -
                       integral[size_t(y1) * (w + 1) + x0] + integral[size_t(y0) * (w + 1) + x0];
      out[size_t(y) * w + x] = s / double((y1 - y0) * (x1 - x0));
    }
  }
}

}  // namespace

ViewScore compareOverMask(std::span<const uint8_t> rendered, std::span<const uint8_t> truth,
                          std::span<const uint8_t> mask, int width, int height) {
  const size_t n = size_t(width) * height;
  if (rendered.size() != n * 4 || truth.size() != n * 4 || mask.size() != n)
    throw Error("compareOverMask: images of " + std::to_string(width) + "x" +
                std::to_string(height) + " RGBA8 and a one-byte mask expected");
  ViewScore score;
  double squared = 0, matte_squared = 0, missed_squared = 0;
  int64_t missed = 0, beyond = 0;
  std::vector<double> a(n), b(n);
  for (size_t i = 0; i < n; ++i) {
    // The matte: the render over black against the image through the mask. The render is a view
    // as the studio shows it (finishSingleProcessView, PartialImageBlender): opaque where drawn,
    // premultiplied where its silhouette is feathered, so its colour is the view over black.
    // Missed and beyond count the pixels it covers at least half.
    const bool drawn = rendered[4 * i + 3] >= 128;
    if (mask[i] || rendered[4 * i + 3] != 0) {
      missed += mask[i] && !drawn;
      beyond += !mask[i] && drawn;
      for (int k = 0; k < 3; ++k) {
        const double d = double(rendered[4 * i + k]) - (mask[i] ? truth[4 * i + k] : 0);
        matte_squared += d * d;
      }
    }
    // Luma for SSIM, the same black outside the mask in both: the windows at the silhouette
    // compare the actor, not the renderer's empty background with the camera's green screen.
    if (!mask[i]) {
      a[i] = b[i] = 0;
      continue;
    }
    a[i] = 0.299 * rendered[4 * i] + 0.587 * rendered[4 * i + 1] + 0.114 * rendered[4 * i + 2];
    b[i] = 0.299 * truth[4 * i] + 0.587 * truth[4 * i + 1] + 0.114 * truth[4 * i + 2];
    ++score.pixels;
    double e = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = double(rendered[4 * i + k]) - truth[4 * i + k];
      e += d * d;
    }
    squared += e;
    if (!drawn) missed_squared += e;
  }
  const auto psnr = [](double squared, int64_t pixels) {
    const double mse = squared / (3.0 * pixels);
    return mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : 100.0;
  };
  if (score.pixels == 0) {
    // No actor in this view: nothing to score over the mask (not 0 dB, which an average would
    // take for a figure); the matte still charges what was drawn.
    constexpr double kUnmeasured = std::numeric_limits<double>::quiet_NaN();
    score.psnr_db = score.ssim = score.missed_pct = score.beyond_pct = kUnmeasured;
    score.missed_error_pct = kUnmeasured;
    score.matte_psnr_db = beyond > 0 ? psnr(matte_squared, beyond) : kUnmeasured;
    return score;
  }
  score.psnr_db = psnr(squared, score.pixels);
  score.matte_psnr_db = psnr(matte_squared, score.pixels + beyond);
  score.missed_pct = 100.0 * missed / score.pixels;
  score.beyond_pct = 100.0 * beyond / score.pixels;
  score.missed_error_pct = squared > 0 ? 100.0 * missed_squared / squared : 0.0;
  // SSIM of luma with 7x7 box windows.
  std::vector<double> aa(n), bb(n), ab(n), ma, mb, maa, mbb, mab;
  for (size_t i = 0; i < n; ++i) aa[i] = a[i] * a[i], bb[i] = b[i] * b[i], ab[i] = a[i] * b[i];
  boxMean(a, width, height, 3, ma);
  boxMean(b, width, height, 3, mb);
  boxMean(aa, width, height, 3, maa);
  boxMean(bb, width, height, 3, mbb);
  boxMean(ab, width, height, 3, mab);
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double ssim = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!mask[i]) continue;
    const double va = maa[i] - ma[i] * ma[i], vb = mbb[i] - mb[i] * mb[i],
                 cov = mab[i] - ma[i] * mb[i];
    ssim += ((2 * ma[i] * mb[i] + c1) * (2 * cov + c2)) /
            ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2));
  }
  score.ssim = ssim / score.pixels;
  return score;
}

void imageToRgba(const ImageView& image, std::vector<uint8_t>& rgba) {
  rgba.resize(size_t(image.width) * image.height * 4);
  if (isBayer(image.format)) {
    demosaicBayerToRgba(image, rgba.data());
    return;
  }
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb c = colourAt(image, x, y);
      uint8_t* p = &rgba[4 * (size_t(y) * image.width + x)];
      p[0] = uint8_t(c.r), p[1] = uint8_t(c.g), p[2] = uint8_t(c.b), p[3] = 255;
    }
  }
}

ViewScore leaveOneOut(LumigraphRenderer& renderer, const Rig& rig,
                      const std::vector<std::vector<uint8_t>>& truth,
                      const std::vector<std::vector<uint8_t>>& masks, int left_out,
                      std::vector<uint8_t>* rendered) {
  const int n = rig.cameraCount();
  std::vector<bool> active(n, true);
  active.at(left_out) = false;
  renderer.setActive(active);
  const Camera& camera = rig.camera(left_out);
  std::vector<uint8_t> own;
  std::vector<uint8_t>& view = rendered ? *rendered : own;
  renderer.render(camera, view);
  renderer.setActive(std::vector<bool>(n, true));
  finishSingleProcessView(view, camera.width(), camera.height());
  return compareOverMask(view, truth.at(left_out), masks.at(left_out), camera.width(),
                         camera.height());
}

void comparisonPicture(std::span<const uint8_t> rendered, std::span<const uint8_t> truth,
                       std::span<const uint8_t> mask, int width, int height,
                       ComparisonPicture& picture) {
  const size_t n = size_t(width) * height;
  if (rendered.size() != n * 4 || truth.size() != n * 4 || mask.size() != n)
    throw Error("comparisonPicture: images of " + std::to_string(width) + "x" +
                std::to_string(height) + " RGBA8 and a one-byte mask expected");
  int x0 = width, y0 = height, x1 = -1, y1 = -1;  // what holds the actor or was drawn
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      if (!mask[i] && rendered[4 * i + 3] == 0) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  if (x1 < 0) {
    x0 = y0 = 0, x1 = width - 1, y1 = height - 1;
  } else {
    constexpr int m = ComparisonPicture::kPictureMargin;
    x0 = std::max(0, x0 - m), y0 = std::max(0, y0 - m);
    x1 = std::min(width - 1, x1 + m), y1 = std::min(height - 1, y1 + m);
  }
  const int w = x1 - x0 + 1, h = y1 - y0 + 1;
  picture.width = 3 * w;
  picture.height = h;
  picture.rgb.assign(size_t(picture.width) * h * 3, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y + y0) * width + (x + x0);
      uint8_t* out = &picture.rgb[(size_t(y) * picture.width + x) * 3];
      uint8_t* image = out + size_t(w) * 3;
      uint8_t* error = out + size_t(w) * 6;
      const uint8_t* r = &rendered[4 * i];
      const uint8_t* t = &truth[4 * i];
      const bool drawn = r[3] != 0;
      for (int k = 0; k < 3; ++k) {
        out[k] = drawn ? r[k] : 0;
        image[k] = t[k];
      }
      if (mask[i] && !drawn) {
        error[0] = 255;
      } else if (!mask[i] && drawn) {
        error[1] = 128, error[2] = 255;
      } else if (mask[i]) {
        const int d = std::abs(r[0] - t[0]) + std::abs(r[1] - t[1]) + std::abs(r[2] - t[2]);
        error[0] = error[1] = error[2] = uint8_t(std::min(255, 4 * d / 3));
      }
    }
  }
}

std::vector<ViewScore> leaveOneOut(LumigraphRenderer& renderer, const Rig& rig,
                                   const std::vector<std::vector<uint8_t>>& truth,
                                   const std::vector<std::vector<uint8_t>>& masks) {
  std::vector<ViewScore> scores;
  for (int c = 0; c < rig.cameraCount(); ++c)
    scores.push_back(leaveOneOut(renderer, rig, truth, masks, c));
  return scores;
}

}  // namespace lumistage
