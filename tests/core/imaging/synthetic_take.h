#pragma once

// A take filmed without a green screen, made up to test mask repair (TakePlate): a textured
// background with sensor noise, a figure that walks across it (its near foot planted at one spot
// all take long, as on a treadmill) and casts a shadow, a bystander swaying in a corner, and
// masks of the figure as a segmenter might give them, with errors put in where the test knows.
#include <algorithm>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace lumistage::testing {

// What to make: the size, how long the figure stands still at first (then it walks across the
// rest of the take), in which frames the given masks are wrong and how.
struct SyntheticTakeSpec {
  int frames = 24;
  int width = 320, height = 240;  // at least these: the figure's size is fixed
  int still = 0;
  std::vector<int> torso_missing = {8, 9, 10, 11};  // the given masks lack the torso
  std::vector<int> blob_frames = {3, 4, 5, 6};      // they take in a patch of background
  std::vector<int> planted_missing = {14, 15};      // they lack the planted foot
  std::vector<int> empty;                           // they are empty (the segmenter found nobody)
  uint32_t seed = 7;
};

struct SyntheticTake {
  SyntheticTakeSpec spec;
  int width = 0, height = 0;
  std::vector<cv::Mat> images;     // RGB8
  std::vector<cv::Mat> truth;      // the figure, 0/255
  std::vector<cv::Mat> given;      // the truth with the spec's errors
  std::vector<cv::Mat> shadow;     // the figure's shadow (in no mask)
  std::vector<cv::Mat> bystander;  // the bystander (in no mask)
  std::vector<cv::Mat> patch;      // a patch of the figure the background's colour
  cv::Rect blob;                   // the patch of background in blob_frames' masks
  cv::Point planted;               // the planted foot's centre: the figure covers it always
};

inline bool listed(const std::vector<int>& frames, int f) {
  return std::find(frames.begin(), frames.end(), f) != frames.end();
}

inline SyntheticTake makeSyntheticTake(const SyntheticTakeSpec& spec = {}) {
  SyntheticTake take;
  take.spec = spec;
  const int width = spec.width, height = spec.height, frames = spec.frames;
  take.width = width, take.height = height;
  std::mt19937 random(spec.seed);
  // The background: blues, greys and greens in patches 12 to 40 pixels across, softened.
  cv::Mat background(height, width, CV_8UC3, cv::Scalar(70, 110, 150));
  std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), side(12, 40);
  std::uniform_int_distribution<int> r(30, 110), g(70, 150), b(110, 200);
  for (int i = 0; i < 160; ++i)
    cv::rectangle(background, cv::Rect(x(random), y(random), side(random), side(random)),
                  cv::Scalar(r(random), g(random), b(random)), cv::FILLED);
  cv::GaussianBlur(background, background, {5, 5}, 0);
  take.planted = {width / 2, height - 28};
  take.blob = {width - 120, 20, 40, 30};
  for (int f = 0; f < frames; ++f) {
    const int walking = frames - spec.still;
    const double t = f < spec.still || walking < 2 ? 0.0 : double(f - spec.still) / (walking - 1);
    const int cx = int(90 + t * (width - 160)), hip = height - 75;
    cv::Mat truth(height, width, CV_8U, cv::Scalar(0)), torso = truth.clone();
    cv::ellipse(torso, {cx, hip - 35}, {22, 38}, 0, 0, 360, 255, cv::FILLED);
    cv::circle(truth, {cx, hip - 86}, 14, 255, cv::FILLED);
    cv::line(truth, {cx - 8, hip}, take.planted, 255, 12);
    cv::line(truth, {cx + 8, hip}, {cx + 24, height - 22}, 255, 12);
    cv::circle(truth, take.planted, 9, 255, cv::FILLED);
    truth |= torso;
    // The shadow falls beside the far foot, off the figure: the ground darkened, its colour kept.
    cv::Mat shadow(height, width, CV_8U, cv::Scalar(0));
    cv::ellipse(shadow, {cx + 55, height - 14}, {28, 7}, 0, 0, 360, 255, cv::FILLED);
    shadow &= ~truth;
    cv::Mat bystander(height, width, CV_8U, cv::Scalar(0));
    const int sway = int(4 * std::sin(f * 0.9));
    cv::ellipse(bystander, {24 + sway, 36}, {9, 24}, 0, 0, 360, 255, cv::FILLED);
    cv::Mat image = background.clone();
    image.setTo(cv::Scalar(200, 60, 70), bystander);
    cv::Mat dimmed;
    background.convertTo(dimmed, -1, 0.6);
    dimmed.copyTo(image, shadow);
    image.setTo(cv::Scalar(215, 160, 125), truth);
    // A patch of the figure the colour of what is behind it (a shirt the wall's colour).
    cv::Mat patch(height, width, CV_8U, cv::Scalar(0));
    patch(cv::Rect(cx - 5, hip - 40, 10, 10)).setTo(255);
    background.copyTo(image, patch);
    cv::Mat noise(height, width, CV_16SC3);
    cv::randn(noise, 0, 2);
    cv::Mat noisy;
    image.convertTo(noisy, CV_16SC3);
    noisy += noise;
    noisy.convertTo(image, CV_8UC3);
    cv::Mat given = truth.clone();
    if (listed(spec.torso_missing, f)) given.setTo(0, torso & ~(truth - torso));
    if (listed(spec.blob_frames, f)) given(take.blob).setTo(255);
    if (listed(spec.planted_missing, f)) cv::circle(given, take.planted, 14, 0, cv::FILLED);
    if (listed(spec.empty, f)) given.setTo(0);
    take.images.push_back(image);
    take.truth.push_back(truth);
    take.given.push_back(given);
    take.shadow.push_back(shadow);
    take.bystander.push_back(bystander);
    take.patch.push_back(patch);
  }
  return take;
}

// |a and b| / |a or b| of two 0/non-zero masks (1 when both are empty).
inline double iou(const cv::Mat& a, const cv::Mat& b) {
  const int both = cv::countNonZero((a != 0) & (b != 0));
  const int either = cv::countNonZero((a != 0) | (b != 0));
  return either == 0 ? 1.0 : double(both) / either;
}

}  // namespace lumistage::testing
