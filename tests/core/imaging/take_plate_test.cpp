// Masks of a take filmed without a green screen, repaired from a clean plate learnt from the take
// itself (TakePlate), on a made-up take whose true masks are known (synthetic_take.h).
#include "core/imaging/take_plate.h"

#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/base/error.h"
#include "tests/core/imaging/synthetic_take.h"

namespace lumistage {
namespace {

using testing::iou;
using testing::makeSyntheticTake;
using testing::SyntheticTake;
using testing::SyntheticTakeSpec;

ImageView rgb(const cv::Mat& image) {
  return {PixelFormat::kRgb8, image.cols, image.rows, image.data};
}
ImageView mono(const cv::Mat& mask) {
  return {PixelFormat::kMono8, mask.cols, mask.rows, mask.data};
}

cv::Mat asMat(const PlateRepair& r, const SyntheticTake& take) {
  return cv::Mat(take.height, take.width, CV_8U, const_cast<uint8_t*>(r.mask.data())).clone();
}

// The take's plate, learnt from every frame.
TakePlate learnt(const SyntheticTake& take, const TakePlateOptions& options = {}) {
  TakePlate plate("cam01", take.width, take.height, options);
  for (int f : TakePlate::framesToLearn(int(take.images.size()), 32))
    plate.add(rgb(take.images[size_t(f)]), mono(take.given[size_t(f)]));
  plate.learn();
  return plate;
}

// Of the frames listed, the share of `region`'s pixels in `masks`.
double shareIn(const std::vector<cv::Mat>& masks, const std::vector<cv::Mat>& region,
               const std::vector<int>& frames) {
  int in = 0, all = 0;
  for (int f : frames) {
    in += cv::countNonZero(masks[size_t(f)] & region[size_t(f)]);
    all += cv::countNonZero(region[size_t(f)]);
  }
  return all == 0 ? 0.0 : double(in) / all;
}

TEST(TakePlate, RepairedMasksAreCloserToTheTruthThanTheGivenOnes) {
  const SyntheticTake take = makeSyntheticTake();
  const TakePlate plate = learnt(take);
  // Only where the figure stands all take long (the planted foot and its leg) is the plate unknown.
  EXPECT_GT(plate.knownShare(), 0.95);
  std::vector<cv::Mat> repaired;
  std::vector<double> before, after;
  for (size_t f = 0; f < take.images.size(); ++f) {
    const PlateRepair r = plate.repair(rgb(take.images[f]), mono(take.given[f]));
    repaired.push_back(asMat(r, take));
    before.push_back(iou(take.given[f], take.truth[f]));
    after.push_back(iou(repaired.back(), take.truth[f]));
    EXPECT_EQ(r.given, size_t(cv::countNonZero(take.given[f])));
    EXPECT_EQ(r.repaired, size_t(cv::countNonZero(repaired.back())));
    EXPECT_NEAR(r.changed(), 1 - iou(repaired.back(), take.given[f]), 1e-9);
  }
  const double mean_before = std::accumulate(before.begin(), before.end(), 0.0) / before.size();
  const double mean_after = std::accumulate(after.begin(), after.end(), 0.0) / after.size();
  EXPECT_GT(mean_after, 0.92);  // 0.93: the key takes in part of the ring of pixels the figure
  // covers in part
  EXPECT_GT(mean_after, mean_before + 0.05) << "given " << mean_before;
  for (size_t f = 0; f < take.images.size(); ++f)
    EXPECT_GT(after[f], 0.85) << "frame " << f << " (given " << before[f] << ")";
  // The torso the given masks missed is found again.
  for (int f : take.spec.torso_missing) {
    EXPECT_LT(before[size_t(f)], 0.6) << "frame " << f;
    EXPECT_GT(after[size_t(f)], 0.9) << "frame " << f;
  }
  // The patch of background they took in is dropped.
  for (int f : take.spec.blob_frames)
    EXPECT_LT(cv::countNonZero(repaired[size_t(f)](take.blob)), take.blob.area() / 50)
        << "frame " << f;
  // Neither the bystander (keyed, but apart from the figure) nor the figure's shadow is taken in.
  std::vector<int> every(take.images.size());
  std::iota(every.begin(), every.end(), 0);
  EXPECT_LT(shareIn(repaired, take.bystander, every), 0.01);
  EXPECT_LT(shareIn(repaired, take.shadow, every), 0.05);
  // A patch of the figure the colour of the background behind it keys as background: a hole,
  // filled.
  EXPECT_GT(shareIn(repaired, take.patch, every), 0.95);
}

// The figure stands still for most of the take, and the given masks miss its torso in a run of
// those frames: the few frames that leave the torso's pixels free show it more often than the
// background. Those pixels' plate is unknown (fewer than half the frames leave them free), so the
// frames whose masks have the torso keep it; learnt from those few frames the plate would be the
// torso, and every frame would lose it.
TEST(TakePlate, ATorsoMissedWhileTheActorStandsStillDoesNotBecomeThePlate) {
  SyntheticTakeSpec spec;
  spec.still = 20;
  spec.torso_missing = {2, 3, 4, 5, 6};
  spec.blob_frames = {};
  spec.planted_missing = {};
  const SyntheticTake take = makeSyntheticTake(spec);
  auto worst = [&](const TakePlate& plate) {
    double lowest = 1;
    for (size_t f = 0; f < take.images.size(); ++f)
      if (!testing::listed(spec.torso_missing, int(f)))
        lowest = std::min(lowest,
                          iou(asMat(plate.repair(rgb(take.images[f]), mono(take.given[f])), take),
                              take.truth[f]));
    return lowest;
  };
  EXPECT_GT(worst(learnt(take)), 0.9);
  TakePlateOptions any_three;  // known wherever three frames leave a pixel free
  any_three.min_share = 0;
  EXPECT_LT(worst(learnt(take, any_three)), 0.8);
}

TEST(TakePlate, WhereTheActorAlwaysStandsTheGivenMaskIsKept) {
  const SyntheticTake take = makeSyntheticTake();
  const TakePlate plate = learnt(take);
  const cv::Point p = take.planted;
  EXPECT_EQ(plate.known().at<uint8_t>(p), 0);
  for (size_t f = 0; f < take.images.size(); ++f) {
    const PlateRepair r = plate.repair(rgb(take.images[f]), mono(take.given[f]));
    const bool given = take.given[f].at<uint8_t>(p) != 0;
    // The plate cannot tell: the given mask is taken as it is, right or (two frames) wrong.
    EXPECT_EQ(r.mask[size_t(p.y) * take.width + p.x] != 0, given) << "frame " << f;
    EXPECT_EQ(given, !testing::listed(take.spec.planted_missing, int(f)));
  }
}

TEST(TakePlate, LearnsFromFramesSpreadOverTheTake) {
  EXPECT_EQ(TakePlate::framesToLearn(5, 32), (std::vector<int>{0, 1, 2, 3, 4}));
  const std::vector<int> frames = TakePlate::framesToLearn(1000, 32);
  ASSERT_EQ(frames.size(), 32u);
  EXPECT_EQ(frames.front(), 0);
  EXPECT_EQ(frames.back(), 999);
  for (size_t i = 1; i < frames.size(); ++i) {
    EXPECT_GT(frames[i], frames[i - 1]);
    EXPECT_NEAR(frames[i] - frames[i - 1], 999.0 / 31, 1.0);
  }
  EXPECT_EQ(TakePlate::framesToLearn(1, 32), std::vector<int>{0});
  EXPECT_TRUE(TakePlate::framesToLearn(0, 32).empty());
}

// A frame whose given mask is empty (the segmenter found nobody): the figure keys against the
// plate, and is kept for it reaches where the figure stands all take long (the planted foot, where
// the plate is unknown); the foot and the leg just above it, which only the given mask could say,
// are missed.
TEST(TakePlate, AnActorTheGivenMaskMissesIsKeptWhereHeReachesWhereHeAlwaysStands) {
  SyntheticTakeSpec spec;
  spec.empty = {12};
  const SyntheticTake take = makeSyntheticTake(spec);
  const TakePlate plate = learnt(take);
  const PlateRepair r = plate.repair(rgb(take.images[12]), mono(take.given[12]));
  EXPECT_EQ(r.given, 0u);
  EXPECT_GT(iou(asMat(r, take), take.truth[12]), 0.7);  // 0.75: the leg near the foot missed too
  EXPECT_EQ(r.mask[size_t(take.planted.y) * take.width + take.planted.x], 0);
}

// Two frames cannot outvote a mask's error: the plate knows no pixel, every mask stays as given
// (its small holes filled).
TEST(TakePlate, FromFewerThanThreeFramesEveryMaskStaysAsGiven) {
  const SyntheticTake take = makeSyntheticTake();
  TakePlate plate("cam01", take.width, take.height);
  for (int f : {0, 9}) plate.add(rgb(take.images[size_t(f)]), mono(take.given[size_t(f)]));
  plate.learn();
  EXPECT_EQ(plate.knownShare(), 0.0);
  const PlateRepair r = plate.repair(rgb(take.images[9]), mono(take.given[9]));
  EXPECT_EQ(r.removed, 0u);
  EXPECT_LT(r.added, size_t(take.width * take.height / 1000));
  EXPECT_EQ(r.fallback, r.repaired);
}

// Large cameras are worked on scaled down; the masks come back at the camera's size.
TEST(TakePlate, ALargeCameraIsRepairedAtItsOwnSize) {
  SyntheticTakeSpec spec;
  spec.frames = 16, spec.width = 640, spec.height = 480;
  const SyntheticTake take = makeSyntheticTake(spec);
  TakePlateOptions options;
  options.max_pixels = 320 * 240;
  TakePlate plate("cam01", take.width, take.height, options);
  EXPECT_EQ(plate.plate().size(), cv::Size());
  for (size_t f = 0; f < take.images.size(); ++f)
    plate.add(rgb(take.images[f]), mono(take.given[f]));
  plate.learn();
  EXPECT_EQ(plate.plate().size(), cv::Size(320, 240));
  const int f = spec.torso_missing[1];
  const PlateRepair r = plate.repair(rgb(take.images[size_t(f)]), mono(take.given[size_t(f)]));
  ASSERT_EQ(r.mask.size(), size_t(640 * 480));
  EXPECT_GT(iou(asMat(r, take), take.truth[size_t(f)]), 0.85);
}

// A camera's own Bayer images (a take the nodes recorded) are demosaiced before learning.
TEST(TakePlate, LearnsFromBayerImages) {
  const SyntheticTake take = makeSyntheticTake();
  std::vector<Image> bayer(take.images.size());
  for (size_t f = 0; f < take.images.size(); ++f) {
    cv::Mat rgba;
    cv::cvtColor(take.images[f], rgba, cv::COLOR_RGB2RGBA);
    rgbaToImage(rgba.data, take.width, take.height, PixelFormat::kBayerGrbg8, bayer[f]);
  }
  TakePlate plate("cam01", take.width, take.height);
  for (size_t f = 0; f < take.images.size(); ++f) plate.add(bayer[f].view(), mono(take.given[f]));
  plate.learn();
  for (int f : take.spec.torso_missing)
    EXPECT_GT(iou(asMat(plate.repair(bayer[size_t(f)].view(), mono(take.given[size_t(f)])), take),
                  take.truth[size_t(f)]),
              0.85)
        << "frame " << f;
}

template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TakePlate, BadInputIsAPreciseError) {
  SyntheticTakeSpec spec;
  spec.frames = 4;
  const SyntheticTake take = makeSyntheticTake(spec);
  TakePlate plate("cam02", take.width, take.height);
  const cv::Mat small(100, 80, CV_8U, cv::Scalar(0));
  EXPECT_EQ(errorOf([&] { plate.add(rgb(take.images[0]), mono(small)); }),
            "camera 'cam02': a 80x100 mono8 mask, expected 320x240 mono8 (the camera's)");
  const ImageView bayer{PixelFormat::kBayerRggb8, take.width, take.height, take.given[0].data};
  EXPECT_EQ(errorOf([&] { plate.add(rgb(take.images[0]), bayer); }),
            "camera 'cam02': a 320x240 bayer_rggb8 mask, expected 320x240 mono8 (the camera's)");
  cv::Mat large;
  cv::resize(take.images[0], large, {640, 480});
  EXPECT_EQ(errorOf([&] { plate.add(rgb(large), mono(take.given[0])); }),
            "camera 'cam02': a 640x480 image, the camera's are 320x240");
  EXPECT_EQ(errorOf([&] { plate.repair(rgb(take.images[0]), mono(take.given[0])); }),
            "camera 'cam02': the take plate is not learnt");
  // A camera without a frame to learn from.
  EXPECT_EQ(errorOf([&] { plate.learn(); }), "camera 'cam02': no frames to learn a plate from");
  TakePlateOptions two;
  two.frames = 2;
  two.min_frames = 1;
  TakePlate few("cam03", take.width, take.height, two);
  few.add(rgb(take.images[0]), mono(take.given[0]));
  few.add(rgb(take.images[1]), mono(take.given[1]));
  EXPECT_EQ(errorOf([&] { few.add(rgb(take.images[2]), mono(take.given[2])); }),
            "camera 'cam03': a take plate learns from at most 2 frames");
  EXPECT_NE(errorOf([] { TakePlate("cam04", 0, 10); }).find("a take plate of 0x10 pixels"),
            std::string::npos);
  TakePlateOptions wrong;
  wrong.frames = 100;
  EXPECT_NE(errorOf([&] { TakePlate("cam04", 10, 10, wrong); }).find("1 <= frames <= 64"),
            std::string::npos);
}

}  // namespace
}  // namespace lumistage
