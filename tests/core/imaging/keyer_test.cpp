// Keying against the virtual studio's truth: the silhouette masks the renderer knows exactly.
#include "core/imaging/keyer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/base/error.h"
#include "core/imaging/clean_plate.h"
#include "core/imaging/silhouettes.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/sim/reference_studio.h"

namespace lumistage {
namespace {

struct Agreement {
  size_t both = 0, either = 0, wrong = 0, total = 0;
  double iou() const { return double(both) / double(either); }
  double errorRate() const { return double(wrong) / double(total); }
};

template <typename Key>
Agreement compare(const Key& key, const ImageView& image, const std::vector<uint8_t>& truth) {
  Agreement a;
  for (int y = 0; y < image.height; y += 2) {
    for (int x = 0; x < image.width; x += 2) {
      const bool keyed = key.isForeground(image, x, y);
      const bool actor = truth[size_t(y) * image.width + x] > 0;
      a.both += keyed && actor;
      a.either += keyed || actor;
      a.wrong += keyed != actor;
      ++a.total;
    }
  }
  return a;
}

class KeyerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    studio_ = new VirtualStudio(testing::referenceStudioOnRing(4000, 4, 512, 384), 30);
  }
  static void TearDownTestSuite() {
    delete studio_;
    studio_ = nullptr;
  }
  static VirtualStudio* studio_;
};

VirtualStudio* KeyerTest::studio_ = nullptr;

TEST_F(KeyerTest, GreenScreenKeyMatchesTheTrueSilhouetteOnBayerImages) {
  StudioFrame frame;
  studio_->renderFrame(20, frame);  // mid-walk
  std::vector<uint8_t> empty;
  for (int c = 0; c < studio_->rig().cameraCount(); ++c) {
    const Camera& camera = studio_->rig().camera(c);
    Image image, screen;
    rgbaToImage(frame.images[c].data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8,
                image);
    studio_->renderEmptyStage(c, 0, empty);
    rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8, screen);
    GreenScreenKeyer keyer;
    const int threshold = keyer.learnScreen(screen.view());
    EXPECT_GT(threshold, 12);
    // The reference screen is bright enough: the nodes do not warn of it.
    EXPECT_GE(keyer.screenExcess(), GreenScreenKeyer::kDimScreenExcess) << camera.name();
    const Agreement a = compare(keyer, image.view(), frame.masks[c]);
    // Disagreement is confined to the silhouette's edge (a Bayer cell straddles it).
    EXPECT_GT(a.iou(), 0.93) << camera.name() << " threshold " << threshold;
    EXPECT_LT(a.errorRate(), 0.004) << camera.name();
  }
}

// Something neutral in a tenth of the view while the screen is learnt (a black suit, grey truss,
// an unlit floor; grey here, with the sensor's noise): the screen's darkest excess and the
// threshold are the screen's still. They fell to 1 and to the minimum of 12 (the screen said too
// dim, the actor's edges keyed as screen: 6% of the actor missed).
TEST_F(KeyerTest, SomethingGreyInViewDoesNotTeachTheKeyThatTheScreenIsGrey) {
  std::vector<uint8_t> empty;
  const Camera& camera = studio_->rig().camera(0);
  studio_->renderEmptyStage(0, 0, empty);
  Image clean, grey;
  rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8, clean);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  for (int y = 0; y < camera.height(); ++y) {
    for (int x = 0; x < camera.width() / 10; ++x) {
      uint8_t* p = &empty[4 * (size_t(y) * camera.width() + x)];
      for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::clamp(40.0f + noise(rng), 0.0f, 255.0f));
    }
  }
  rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8, grey);
  GreenScreenKeyer from_clean, from_grey;
  from_clean.learnScreen(clean.view());
  from_grey.learnScreen(grey.view());
  EXPECT_GE(from_grey.screenExcess(), GreenScreenKeyer::kDimScreenExcess);
  EXPECT_NEAR(from_grey.threshold(), from_clean.threshold(), 3);
  EXPECT_GT(from_grey.threshold(), 30);
  // Grey everywhere (the lights off, a real sensor's noise under a lens cap): no screen at all, the
  // threshold as it was. (Every sample then fell below the screen's least, and an empty list was
  // read.)
  for (size_t p = 0; p < empty.size(); p += 4)
    for (int k = 0; k < 3; ++k)
      empty[p + k] = uint8_t(std::clamp(40.0f + noise(rng), 0.0f, 255.0f));
  rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8, grey);
  GreenScreenKeyer from_dark;
  EXPECT_EQ(from_dark.learnScreen(grey.view()), GreenScreenKeyer().threshold());
  EXPECT_EQ(from_dark.screenExcess(), 0);
}

// The lights dim after the screen was learnt: the key learnt then takes the screen's darker parts
// for the actor; following a measurement of the dimmed screen keys it as before. A measurement of
// the same screen (its noise, the actor moved) leaves the key alone.
TEST_F(KeyerTest, AKeyFollowsAScreenThatDimmedSinceItWasLearnt) {
  StudioFrame frame;
  studio_->renderFrame(10, frame);
  const Camera& camera = studio_->rig().camera(2);
  Image lit, dimmed;
  rgbaToImage(frame.images[2].data(), camera.width(), camera.height(), PixelFormat::kRgb8, lit);
  std::vector<uint8_t> dim = frame.images[2];
  for (size_t p = 0; p < dim.size(); ++p) dim[p] = uint8_t(dim[p] * 0.55f);
  rgbaToImage(dim.data(), camera.width(), camera.height(), PixelFormat::kRgb8, dimmed);

  GreenScreenKeyer keyer;
  keyer.learnScreen(lit.view());
  const int learnt = keyer.threshold();
  GreenScreenKeyer again;
  again.learnScreen(lit.view());
  EXPECT_FALSE(keyer.follow(again));
  EXPECT_EQ(keyer.threshold(), learnt);

  const Agreement before = compare(keyer, dimmed.view(), frame.masks[2]);
  GreenScreenKeyer measured;
  measured.learnScreen(dimmed.view());
  EXPECT_TRUE(keyer.follow(measured));
  EXPECT_LT(keyer.threshold(), learnt);
  EXPECT_EQ(keyer.screenExcess(), measured.screenExcess());
  const Agreement after = compare(keyer, dimmed.view(), frame.masks[2]);
  EXPECT_GT(before.errorRate(), 0.02) << "the old key should lose the dimmed screen";
  EXPECT_LT(after.errorRate(), 0.006);
  EXPECT_GT(after.iou(), 0.95);

  // A measurement that saw no screen (a lens cap) changes nothing.
  std::vector<uint8_t> black(frame.images[2].size(), 0);
  Image dark;
  rgbaToImage(black.data(), camera.width(), camera.height(), PixelFormat::kRgb8, dark);
  GreenScreenKeyer none;
  none.learnScreen(dark.view());
  const int followed = keyer.threshold();
  EXPECT_FALSE(keyer.follow(none));
  EXPECT_EQ(keyer.threshold(), followed);
}

TEST_F(KeyerTest, BackgroundModelLearnedFromTheEmptyStageFindsTheActor) {
  StudioFrame frame;
  studio_->renderFrame(25, frame);
  std::vector<uint8_t> empty;
  const Camera& camera = studio_->rig().camera(1);
  BackgroundModel model(camera.width(), camera.height());
  for (int take = 0; take < 4; ++take) {
    Image screen;
    studio_->renderEmptyStage(1, take, empty);
    rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kRgb8, screen);
    model.add(screen.view());
  }
  model.learn();
  // A frame of another camera's size, and nothing to learn from: errors naming what, not a read
  // past the model's blocks.
  BackgroundModel other(camera.width() / 2, camera.height());
  Image screen;
  studio_->renderEmptyStage(1, 0, empty);
  rgbaToImage(empty.data(), camera.width(), camera.height(), PixelFormat::kRgb8, screen);
  try {
    other.add(screen.view());
    ADD_FAILURE() << "a frame of another size was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  fmt::format("an empty stage's frame of {}x{}", camera.width(), camera.height())),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(other.learn(), Error);
  EXPECT_THROW(BackgroundModel(0, 10), Error);
  Image image;
  rgbaToImage(frame.images[1].data(), camera.width(), camera.height(), PixelFormat::kRgb8, image);
  const Agreement a = compare(model, image.view(), frame.masks[1]);
  EXPECT_GT(a.iou(), 0.97);
  EXPECT_LT(a.errorRate(), 0.006);
}

// A stage without a green screen (the virtual studio's room: a wooden floor, painted walls,
// posters, a door) keyed on its clean plate, learnt from eight frames of the empty stage: the
// actor's silhouette, pixel by pixel and in a node's low-resolution cells, against the truth, on
// RGB and on Bayer images alike.
TEST(CleanPlate, KeysARoomAsWellAsAGreenScreenIsKeyed) {
  StudioConfig config = testing::referenceStudioOnRing(4000, 4, 512, 384);
  config.look.backdrop = StudioLook::Backdrop::kRoom;
  VirtualStudio studio(config, 30);
  StudioFrame frame;
  studio.renderFrame(20, frame);
  std::vector<uint8_t> empty;
  for (const PixelFormat format : {PixelFormat::kRgb8, PixelFormat::kBayerGrbg8}) {
    for (int c = 0; c < studio.rig().cameraCount(); ++c) {
      SCOPED_TRACE(::testing::Message() << pixelFormatName(format) << ", camera " << c);
      const Camera& camera = studio.rig().camera(c);
      std::vector<Image> plate(8);
      for (int take = 0; take < 8; ++take) {
        studio.renderEmptyStage(c, take, empty);
        rgbaToImage(empty.data(), camera.width(), camera.height(), format, plate[take]);
      }
      const std::shared_ptr<const BackgroundModel> model =
          learnPlate(plate, camera.width(), camera.height());
      ASSERT_TRUE(model);
      EXPECT_EQ(model->frames(), 8);
      Image image;
      rgbaToImage(frame.images[c].data(), camera.width(), camera.height(), format, image);
      // The room is no green screen: its green key loses the actor in the room.
      GreenScreenKeyer green;
      green.learnScreen(image.view());
      EXPECT_LT(compare(green, image.view(), frame.masks[c]).iou(), 0.5);
      const Agreement a = compare(*model, image.view(), frame.masks[c]);
      EXPECT_GT(a.iou(), 0.93);
      EXPECT_LT(a.errorRate(), 0.01);
      // A node's cells, as the tracker gets them.
      LowResSilhouette cells;
      computeSilhouette(*model, image.view(), c, 4, cells);
      size_t agree = 0;
      for (int y = 0; y < cells.height; ++y)
        for (int x = 0; x < cells.width; ++x)
          agree += cells.at(x, y) ==
                   (frame.masks[c][size_t(y * 4 + 2) * camera.width() + x * 4 + 2] > 0);
      EXPECT_GT(double(agree) / (cells.width * cells.height), 0.985);
    }
  }
  // A frame of another size is left out, and counted.
  Image small;
  small.resize(PixelFormat::kRgb8, 16, 16);
  int skipped = 0;
  EXPECT_FALSE(learnPlate({small}, 512, 384, &skipped));
  EXPECT_EQ(skipped, 1);
}

// A hole a clean plate's key leaves inside the actor (his colour is the room's there) is filled;
// the background that reaches the image's border stays, however it winds.
TEST(CleanPlate, HolesInASilhouetteAreFilledAndTheBackgroundKept) {
  const char* rows[] = {
      "..........",  //
      ".####.....",  //
      ".#..#..##.",  //
      ".####..#..",  //
      "#......#.#",  //
      "#.......#.",  //
  };
  LowResSilhouette s;
  s.width = 10, s.height = 6;
  s.bits.assign(8, 0);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 10; ++x)
      if (rows[y][x] == '#') s.set(x, y);
  fillHoles(s);
  for (int y = 0; y < 6; ++y) {
    for (int x = 0; x < 10; ++x) {
      const bool hole = y == 2 && (x == 2 || x == 3);
      EXPECT_EQ(s.at(x, y), rows[y][x] == '#' || hole) << x << ", " << y;
    }
  }
  EXPECT_THROW(BackgroundModel(8, 8, 0.0f), Error);
  BackgroundModel model(8, 8);
  Image empty;
  empty.resize(PixelFormat::kRgb8, 8, 8);
  model.add(empty.view());
  model.learn();
  EXPECT_THROW(model.add(empty.view()), Error);  // learnt already
}

TEST_F(KeyerTest, LowResolutionSilhouetteSamplesCellCentres) {
  StudioFrame frame;
  studio_->renderFrame(10, frame);
  const Camera& camera = studio_->rig().camera(2);
  Image image;
  rgbaToImage(frame.images[2].data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8,
              image);
  GreenScreenKeyer keyer;
  std::vector<uint8_t> mask;
  lowResSilhouette(keyer, image.view(), 8, mask);
  ASSERT_EQ(mask.size(), size_t(64 * 48));
  size_t agree = 0, actor = 0;
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      const bool truth = frame.masks[2][size_t(y * 8 + 4) * camera.width() + x * 8 + 4] > 0;
      agree += (mask[size_t(y) * 64 + x] > 0) == truth;
      actor += truth;
    }
  }
  EXPECT_GT(actor, 30u);
  EXPECT_GT(double(agree) / mask.size(), 0.99);
}

// A pure foreground level (the refinement's colours take only those pixels,
// RefineConfig::colour_purity) is a foreground level with a margin: for the green-screen key and
// for a background learnt from the empty stage alike, a colour mixed a little toward the
// background is the actor's but not purely, one far from it is both, and at purity 1 the two
// tests agree.
TEST(Keyer, APureForegroundLevelIsTheActorsWithAMargin) {
  const Rgb screen{40, 200, 60}, actor{150, 90, 80};
  const auto mix = [&](double share) {  // `share` of the screen's colour in the actor's
    return Rgb{int(std::lround(actor.r + share * (screen.r - actor.r))),
               int(std::lround(actor.g + share * (screen.g - actor.g))),
               int(std::lround(actor.b + share * (screen.b - actor.b)))};
  };
  const GreenScreenKeyer keyer;
  Image empty;
  empty.resize(PixelFormat::kRgb8, 32, 32);
  for (size_t p = 0; p < size_t(32) * 32; ++p) {
    const int noise = int(p % 3) - 1;  // the sensor's: -1, 0, +1
    empty.pixels[3 * p] = uint8_t(screen.r + noise);
    empty.pixels[3 * p + 1] = uint8_t(screen.g + noise);
    empty.pixels[3 * p + 2] = uint8_t(screen.b - noise);
  }
  BackgroundModel model(32, 32);
  model.add(empty.view());
  model.learn();
  const auto check = [&](const auto& key, const char* name) {
    SCOPED_TRACE(name);
    int foreground_only = 0, pure = 0;
    for (double share = 0; share <= 1.0; share += 0.02) {
      const float level = float(key.backgroundLevel(mix(share), 5, 5));
      const bool fg = key.isForegroundLevel(level, 5, 5);
      const bool strict = key.isPureForegroundLevel(level, 5, 5, 0.4f);
      EXPECT_EQ(key.isPureForegroundLevel(level, 5, 5, 1.0f), fg) << share;
      if (strict) {
        EXPECT_TRUE(fg) << share;
      }
      foreground_only += fg && !strict;
      pure += strict;
    }
    EXPECT_TRUE(key.isPureForegroundLevel(float(key.backgroundLevel(actor, 5, 5)), 5, 5, 0.4f));
    EXPECT_GT(foreground_only, 0);
    EXPECT_GT(pure, 0);
  };
  check(keyer, "green screen");
  check(model, "learnt background");
}

TEST(Keyer, CellsAreKeyedByTheMeanOfThePixelsAroundTheirCentre) {
  // Pixel by pixel: 3x3 windows, whole and cut by the edges, against their plain mean; on Bayer,
  // the cells read once and weighted give the mean of the nine pixels' cell colours.
  const int width = 8, height = 6;
  std::vector<uint8_t> rgb(width * height * 3), bayer(width * height);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t((i * 53 + 7) % 256);
  for (size_t i = 0; i < bayer.size(); ++i) bayer[i] = uint8_t((i * 91 + 3) % 256);
  for (const ImageView view : {ImageView{PixelFormat::kRgb8, width, height, rgb.data()},
                               ImageView{PixelFormat::kBayerGrbg8, width, height, bayer.data()}}) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        int sum[3] = {0, 0, 0}, n = 0;
        for (int yy = std::max(0, y - 1); yy <= std::min(height - 1, y + 1); ++yy) {
          for (int xx = std::max(0, x - 1); xx <= std::min(width - 1, x + 1); ++xx) {
            const Rgb c = colourAt(view, xx, yy);
            sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, ++n;
          }
        }
        const Rgb mean = meanColourAround(view, x, y);
        EXPECT_EQ(mean.r, (sum[0] + n / 2) / n) << pixelFormatName(view.format) << x << "," << y;
        EXPECT_EQ(mean.g, (sum[1] + n / 2) / n) << pixelFormatName(view.format) << x << "," << y;
        EXPECT_EQ(mean.b, (sum[2] + n / 2) / n) << pixelFormatName(view.format) << x << "," << y;
      }
    }
  }
  // A cell whose centre pixel alone is the screen's green, its neighbours the actor's grey: keyed
  // as the actor (the mean is grey-green), where the centre pixel alone would say screen.
  std::vector<uint8_t> cell(4 * 4 * 3, 100);
  cell[3 * (2 * 4 + 2) + 0] = 30, cell[3 * (2 * 4 + 2) + 1] = 200, cell[3 * (2 * 4 + 2) + 2] = 30;
  const ImageView view{PixelFormat::kRgb8, 4, 4, cell.data()};
  const GreenScreenKeyer keyer(30);
  EXPECT_FALSE(keyer.isForeground(view, 2, 2));
  EXPECT_TRUE(keyCell(keyer, view, 0, 0, 4));
}

TEST(Keyer, ColourOfABayerPixelComesFromItsCell) {
  // RGGB 2x2 cells: R=10, G=20/30, B=40.
  const uint8_t bayer[8] = {10, 20, 10, 20, 30, 40, 30, 40};
  const ImageView view{PixelFormat::kBayerRggb8, 4, 2, bayer};
  for (int x = 0; x < 4; ++x) {
    for (int y = 0; y < 2; ++y) {
      const Rgb c = colourAt(view, x, y);
      EXPECT_EQ(c.r, 10);
      EXPECT_EQ(c.g, 25);
      EXPECT_EQ(c.b, 40);
    }
  }
}

// An odd-sized mosaic (a sensor read out at 1023x767): the last column and row take the cell
// before them. They read the next row's first pixel, and past the image, before. The image sits in
// a buffer followed by bytes of another colour, which a read past its end would take.
TEST(Keyer, TheLastColumnAndRowOfAnOddSizedMosaicAreReadInsideIt) {
  const int w = 5, h = 3;
  std::vector<uint8_t> buffer(size_t(w) * h + 64, 255);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      buffer[size_t(y) * w + x] = y % 2 == 0 ? (x % 2 == 0 ? 10 : 20) : (x % 2 == 0 ? 30 : 40);
  }
  const ImageView view{PixelFormat::kBayerRggb8, w, h, buffer.data()};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Rgb c = colourAt(view, x, y);
      EXPECT_EQ(c.r, 10) << x << ", " << y;
      EXPECT_EQ(c.g, 25) << x << ", " << y;
      EXPECT_EQ(c.b, 40) << x << ", " << y;
    }
  }
}

}  // namespace
}  // namespace lumistage
