#include "core/imaging/take_plate.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/base/error.h"

namespace lumistage {

namespace {

// The most frames a plate learns from: the per-pixel samples live on the stack.
constexpr int kMaxFrames = 64;
// The blur before keying, in pixels: a frame's noise and its compression's blocks averaged out.
constexpr int kBlur = 5;
// A normal distribution's standard deviation per median absolute deviation.
constexpr float kMadToSigma = 1.4826f;

cv::Mat ellipse(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * radius + 1, 2 * radius + 1});
}

// The median of the first n of `v` (reordered): the lower middle one for an even count.
uint8_t median(uint8_t* v, int n) {
  std::nth_element(v, v + (n - 1) / 2, v + n);
  return v[(n - 1) / 2];
}

// The image as RGB8 (a copy).
cv::Mat toRgb(const ImageView& image) {
  const cv::Mat wrapped(image.height, image.width,
                        image.format == PixelFormat::kRgb8 ? CV_8UC3 : CV_8U,
                        const_cast<uint8_t*>(image.data));
  cv::Mat rgb;
  if (image.format == PixelFormat::kRgb8) {
    rgb = wrapped.clone();
  } else if (image.format == PixelFormat::kMono8) {
    cv::cvtColor(wrapped, rgb, cv::COLOR_GRAY2RGB);
  } else {
    cv::Mat rgba(image.height, image.width, CV_8UC4);
    demosaicBayerToRgba(image, rgba.data);
    cv::cvtColor(rgba, rgb, cv::COLOR_RGBA2RGB);
  }
  return rgb;
}

// The per-pixel maximum of a 3-channel 8-bit image's channels.
cv::Mat channelMax(const cv::Mat& image) {
  cv::Mat c[3], out;
  cv::split(image, c);
  cv::max(c[0], c[1], out);
  cv::max(out, c[2], out);
  return out;
}

// Pixels of `mask` (0/255) in 8-connected regions that none of `touch` reaches are cleared.
cv::Mat keepTouching(const cv::Mat& mask, const cv::Mat& touch) {
  cv::Mat labels;
  const int n = cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<uint8_t> keep(size_t(n), 0);
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    const uint8_t* t = touch.ptr<uint8_t>(y);
    for (int x = 0; x < mask.cols; ++x)
      if (t[x] && l[x]) keep[size_t(l[x])] = 255;
  }
  cv::Mat out(mask.size(), CV_8U);
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < mask.cols; ++x) o[x] = keep[size_t(l[x])];
  }
  return out;
}

// `mask` with its holes (4-connected background regions off the image's border) of at most
// `largest` pixels filled.
cv::Mat fillHoles(const cv::Mat& mask, int largest) {
  cv::Mat background = mask == 0, labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(background, labels, stats, centroids, 4, CV_32S);
  std::vector<uint8_t> fill(size_t(n), 0);
  for (int i = 1; i < n; ++i) {
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), y = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    const bool border = x == 0 || y == 0 || x + w == mask.cols || y + h == mask.rows;
    fill[size_t(i)] = !border && stats.at<int>(i, cv::CC_STAT_AREA) <= largest ? 255 : 0;
  }
  cv::Mat out = mask.clone();
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < mask.cols; ++x) o[x] |= fill[size_t(l[x])];
  }
  return out;
}

}  // namespace

TakePlate::TakePlate(std::string camera, int width, int height, const TakePlateOptions& options)
    : camera_(std::move(camera)), width_(width), height_(height), options_(options) {
  if (width <= 0 || height <= 0)
    throw Error(fmt::format("camera '{}': a take plate of {}x{} pixels", camera_, width, height));
  const TakePlateOptions& o = options;
  if (o.frames < 1 || o.frames > kMaxFrames || o.margin < 0 || o.min_frames < 1 ||
      o.min_frames > o.frames || o.floor < 0 || o.floor > 255 || !(o.spread_k >= 0) ||
      !(o.darkest_shadow > 0 && o.darkest_shadow <= 1) || !(o.shadow_colour >= 0) ||
      !(o.hole >= 0 && o.hole < 1) || !(o.min_share >= 0 && o.min_share <= 1) || o.max_pixels < 1)
    throw Error(fmt::format(
        "take plate: expected 1 <= frames <= {}, 1 <= min_frames <= frames, margin >= 0, floor "
        "0..255, min_share in [0, 1], spread_k >= 0, darkest_shadow in (0, 1], shadow_colour >= 0, "
        "hole in [0, 1), "
        "max_pixels >= 1",
        kMaxFrames));
  const double area = double(width) * height;
  const double scale = area > o.max_pixels ? std::sqrt(o.max_pixels / area) : 1.0;
  work_ = {std::max(1, int(std::lround(width * scale))),
           std::max(1, int(std::lround(height * scale)))};
}

std::vector<int> TakePlate::framesToLearn(int count, int cap) {
  std::vector<int> frames;
  if (count <= 0 || cap <= 0) return frames;
  const int n = std::min(count, cap);
  for (int i = 0; i < n; ++i)
    frames.push_back(n == 1 ? 0 : int(std::lround(double(i) * (count - 1) / (n - 1))));
  return frames;
}

cv::Mat TakePlate::prepareImage(const ImageView& image) const {
  if (image.width != width_ || image.height != height_ || !image.data)
    throw Error(fmt::format("camera '{}': a {}x{} image, the camera's are {}x{}", camera_,
                            image.width, image.height, width_, height_));
  cv::Mat rgb = toRgb(image);
  if (rgb.size() != work_) cv::resize(rgb, rgb, work_, 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(rgb, rgb, {kBlur, kBlur}, 0);
  return rgb;
}

cv::Mat TakePlate::prepareMask(const ImageView& given) const {
  if (given.width != width_ || given.height != height_ || !given.data ||
      given.format != PixelFormat::kMono8)
    throw Error(fmt::format("camera '{}': a {}x{} {} mask, expected {}x{} mono8 (the camera's)",
                            camera_, given.width, given.height, pixelFormatName(given.format),
                            width_, height_));
  const cv::Mat wrapped(height_, width_, CV_8U, const_cast<uint8_t*>(given.data));
  cv::Mat mask = wrapped != 0;
  if (mask.size() != work_) {
    cv::resize(mask, mask, work_, 0, 0, cv::INTER_LINEAR);
    mask = mask > 127;
  }
  return mask;
}

void TakePlate::add(const ImageView& image, const ImageView& given) {
  if (int(frames_.size()) >= options_.frames)
    throw Error(fmt::format("camera '{}': a take plate learns from at most {} frames", camera_,
                            options_.frames));
  cv::Mat frame = prepareImage(image), covered;
  cv::dilate(prepareMask(given), covered, ellipse(options_.margin));
  frames_.push_back(std::move(frame));
  free_.push_back(covered == 0);
}

void TakePlate::learn() {
  const int n = int(frames_.size());
  if (n == 0) throw Error(fmt::format("camera '{}': no frames to learn a plate from", camera_));
  plate_ = cv::Mat(work_, CV_8UC3, cv::Scalar::all(0));
  known_ = cv::Mat(work_, CV_8U, cv::Scalar(0));
  threshold_ = cv::Mat(work_, CV_8U, cv::Scalar(255));
  // Fewer frames than min_frames: nothing is known, every mask stays as given.
  const int min_frames =
      std::max(options_.min_frames, int(std::ceil(options_.min_share * n - 1e-9)));
  cv::parallel_for_(cv::Range(0, work_.height), [&](const cv::Range& rows) {
    uint8_t v[3][kMaxFrames];
    const uint8_t* image[kMaxFrames];
    const uint8_t* free[kMaxFrames];
    for (int y = rows.start; y < rows.end; ++y) {
      for (int i = 0; i < n; ++i) image[i] = frames_[size_t(i)].ptr<uint8_t>(y);
      for (int i = 0; i < n; ++i) free[i] = free_[size_t(i)].ptr<uint8_t>(y);
      uint8_t* plate = plate_.ptr<uint8_t>(y);
      uint8_t* known = known_.ptr<uint8_t>(y);
      uint8_t* threshold = threshold_.ptr<uint8_t>(y);
      for (int x = 0; x < work_.width; ++x) {
        int m = 0;
        for (int i = 0; i < n; ++i) {
          if (!free[i][x]) continue;
          for (int c = 0; c < 3; ++c) v[c][m] = image[i][3 * x + c];
          ++m;
        }
        if (m < min_frames) continue;
        int mad = 0;
        for (int c = 0; c < 3; ++c) {
          const uint8_t mid = median(v[c], m);
          plate[3 * x + c] = mid;
          for (int j = 0; j < m; ++j) v[c][j] = uint8_t(std::abs(int(v[c][j]) - int(mid)));
          mad = std::max(mad, int(median(v[c], m)));
        }
        known[x] = 255;
        const float bound = std::max(float(options_.floor), options_.spread_k * kMadToSigma * mad);
        threshold[x] = uint8_t(std::min(255.0f, std::round(bound)));
      }
    }
  });
  frames_.clear();
  free_.clear();
}

double TakePlate::knownShare() const {
  return known_.empty() ? 0.0 : double(cv::countNonZero(known_)) / double(known_.total());
}

cv::Mat TakePlate::key(const cv::Mat& blurred) const {
  cv::Mat diff, keyed;
  cv::absdiff(blurred, plate_, diff);
  cv::compare(channelMax(diff), threshold_, keyed, cv::CMP_GT);
  // Shadows: the plate dimmed (a = I.P / P.P, the brightness the pixel has of the plate's) with
  // the colour it had (I - aP small against the threshold).
  cv::Mat i, p;
  blurred.convertTo(i, CV_32F);
  plate_.convertTo(p, CV_32F);
  cv::Mat ic[3], pc[3];
  cv::split(i, ic);
  cv::split(p, pc);
  cv::Mat ip = ic[0].mul(pc[0]) + ic[1].mul(pc[1]) + ic[2].mul(pc[2]);
  cv::Mat pp = pc[0].mul(pc[0]) + pc[1].mul(pc[1]) + pc[2].mul(pc[2]) + 1.0f;
  cv::Mat a = ip / pp, residual;
  residual = cv::abs(ic[0] - a.mul(pc[0]));
  cv::max(residual, cv::abs(ic[1] - a.mul(pc[1])), residual);
  cv::max(residual, cv::abs(ic[2] - a.mul(pc[2])), residual);
  cv::Mat bound;
  threshold_.convertTo(bound, CV_32F, options_.shadow_colour);
  const cv::Mat shadow = (a >= options_.darkest_shadow) & (a < 1.0f) & (residual <= bound);
  keyed &= ~shadow;
  return keyed;
}

cv::Mat TakePlate::clean(const cv::Mat& keyed, const cv::Mat& given) const {
  cv::Mat mask = (keyed & known_) | (given & ~known_), near;
  // Near the actor: his mask, or where he stands most of the take (the plate unknown there).
  cv::dilate(given | ~known_, near, ellipse(options_.margin));
  mask = keepTouching(mask, near);
  return fillHoles(mask, int(options_.hole * double(work_.area())));
}

PlateRepair TakePlate::repair(const ImageView& image, const ImageView& given) const {
  if (!learnt()) throw Error(fmt::format("camera '{}': the take plate is not learnt", camera_));
  const cv::Mat frame = prepareImage(image), mask = prepareMask(given);
  cv::Mat repaired = clean(key(frame), mask);
  cv::Mat fallback = repaired & ~known_;
  const cv::Mat full_given = cv::Mat(height_, width_, CV_8U, const_cast<uint8_t*>(given.data)) != 0;
  if (repaired.size() != cv::Size(width_, height_)) {
    cv::resize(repaired, repaired, {width_, height_}, 0, 0, cv::INTER_LINEAR);
    repaired = repaired > 127;
    cv::resize(fallback, fallback, {width_, height_}, 0, 0, cv::INTER_NEAREST);
  }
  PlateRepair r;
  r.mask.assign(repaired.datastart, repaired.dataend);
  r.given = size_t(cv::countNonZero(full_given));
  r.repaired = size_t(cv::countNonZero(repaired));
  r.added = size_t(cv::countNonZero(repaired & ~full_given));
  r.removed = size_t(cv::countNonZero(full_given & ~repaired));
  r.fallback = size_t(cv::countNonZero(fallback));
  return r;
}

Image repairPicture(const TakePlate& plate, const ImageView& image, const ImageView& given,
                    const std::vector<uint8_t>& repaired) {
  const int w = image.width, h = image.height;
  if (given.width != w || given.height != h || repaired.size() != size_t(w) * h)
    throw Error(fmt::format("camera '{}': a repair picture's image and masks differ in size",
                            plate.camera()));
  cv::Mat rgb = toRgb(image), known;
  cv::resize(plate.known(), known, {w, h}, 0, 0, cv::INTER_NEAREST);
  Image out;
  out.resize(PixelFormat::kRgb8, w, h);
  for (int y = 0; y < h; ++y) {
    const uint8_t* src = rgb.ptr<uint8_t>(y);
    const uint8_t* g = given.data + size_t(y) * w;
    const uint8_t* r = repaired.data() + size_t(y) * w;
    const uint8_t* k = known.ptr<uint8_t>(y);
    uint8_t* o = out.pixels.data() + size_t(y) * w * 3;
    for (int x = 0; x < w; ++x, src += 3, o += 3) {
      const bool a = g[x] != 0, b = r[x] != 0;
      uint8_t px[3] = {uint8_t(src[0] / 2), uint8_t(src[1] / 2), uint8_t(src[2] / 2)};
      if (a && b) px[0] = 0, px[1] = 200, px[2] = 0;
      if (!a && b) px[0] = 220, px[1] = 0, px[2] = 0;
      if (a && !b) px[0] = 0, px[1] = 0, px[2] = 220;
      // Where the plate is unknown, purple stripes over whatever is there.
      if (!k[x] && (x + y) / 6 % 2 == 0) px[0] = 160, px[1] = 60, px[2] = 200;
      o[0] = px[0], o[1] = px[1], o[2] = px[2];
    }
  }
  return out;
}

}  // namespace lumistage
