#include "core/capture/session_reader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/base/error.h"
#include "core/body/ply_mesh.h"
#include "core/capture/take_merge.h"
#include "tests/core/capture/capture_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using namespace lumistage::test;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string allWarnings(const SessionReader& reader) {
  std::string out;
  for (const std::string& w : reader.warnings()) out += w + "\n";
  return out;
}

void expectFramesExact(const SessionReader& reader, PixelFormat format, int count) {
  ASSERT_EQ(reader.frameCount(), count);
  std::vector<CameraFrame> frames;
  for (int i = 0; i < count; ++i) {
    EXPECT_EQ(reader.frameId(i), i);
    EXPECT_EQ(reader.timestampNs(i), timestampOf(i));
    reader.readFrame(i, frames);
    const std::vector<Image> expected = frameImages(reader.rig(), format, i);
    ASSERT_EQ(frames.size(), expected.size());
    for (size_t c = 0; c < frames.size(); ++c) {
      EXPECT_EQ(frames[c].camera, int(c));
      EXPECT_EQ(frames[c].frame_id, i);
      EXPECT_EQ(frames[c].timestamp_ns, timestampOf(i));
      EXPECT_EQ(frames[c].image.format, format);
      EXPECT_TRUE(frames[c].image.pixels == expected[c].pixels) << "frame " << i << " cam " << c;
    }
  }
}

TEST(SessionReader, ReadsBackWhatWasWrittenBitExactInEveryPixelFormat) {
  const Rig rig = smallRig();
  for (PixelFormat format : {PixelFormat::kMono8, PixelFormat::kBayerRggb8, PixelFormat::kRgb8}) {
    const fs::path folder = freshFolder(std::string("exact_") + pixelFormatName(format));
    writeSession(folder, rig, format, 4);
    const SessionReader reader(folder);
    EXPECT_EQ(reader.pixelFormat(), format);
    EXPECT_EQ(reader.fps(), 30.0);
    EXPECT_EQ(reader.source(), "test");
    EXPECT_FALSE(reader.hasTruth());
    EXPECT_TRUE(reader.rig() == rig);
    EXPECT_TRUE(reader.warnings().empty()) << allWarnings(reader);
    expectFramesExact(reader, format, 4);
    fs::remove_all(folder);
  }
}

// PNM files (live recording's): the pixels as they are, behind a short header.
TEST(SessionReader, ReadsBackPnmFilesBitExactInEveryPixelFormat) {
  const Rig rig = smallRig();
  for (PixelFormat format : {PixelFormat::kMono8, PixelFormat::kBayerGrbg8, PixelFormat::kRgb8}) {
    const fs::path folder = freshFolder(std::string("pnm_") + pixelFormatName(format));
    writeSession(folder, rig, format, 3, 7, ImageFiles::kPnm);
    EXPECT_TRUE(contains(readFile(folder / "session.yaml"), "\nimage_files: pnm\n"));
    const bool rgb = format == PixelFormat::kRgb8;
    const std::string file = readFile(folder / "cam02" / (rgb ? "000001.ppm" : "000001.pgm"));
    const std::string header = rgb ? "P6\n64 48\n255\n" : "P5\n64 48\n255\n";
    ASSERT_EQ(file.size(), header.size() + 64 * 48 * bytesPerPixel(format));
    EXPECT_EQ(file.substr(0, header.size()), header);
    const SessionReader reader(folder);
    EXPECT_EQ(reader.imageFiles(), ImageFiles::kPnm);
    EXPECT_EQ(reader.imagePath(1, 1).filename(), rgb ? "000001.ppm" : "000001.pgm");
    EXPECT_TRUE(reader.warnings().empty()) << allWarnings(reader);
    ASSERT_EQ(reader.frameCount(), 3);
    std::vector<CameraFrame> frames;
    for (int i = 0; i < 3; ++i) {
      reader.readFrame(i, frames);
      const std::vector<Image> expected = frameImages(rig, format, i, 7);
      for (size_t c = 0; c < frames.size(); ++c) {
        EXPECT_EQ(frames[c].frame_id, i);
        EXPECT_TRUE(frames[c].image.pixels == expected[c].pixels) << "frame " << i << " cam " << c;
      }
    }
    fs::remove_all(folder);
  }
}

// A PNM cut short, or of another size or kind, ends the session before its frame; one damaged
// after opening is an error naming it.
TEST(SessionReader, APnmCutShortOrWrongEndsTheSessionThere) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("pnm_torn");
  writeSession(folder, rig, PixelFormat::kBayerRggb8, 3, 1, ImageFiles::kPnm);  // 2 is the last
  const fs::path pgm = folder / "cam03" / "000002.pgm";
  const std::string whole = readFile(pgm);
  auto firstWarning = [&] {
    const SessionReader reader(folder);
    EXPECT_EQ(reader.frameCount(), 2) << allWarnings(reader);
    return reader.warnings().empty() ? std::string() : reader.warnings()[0];
  };
  truncateFile(pgm, whole.size() - 1);
  std::string w = firstWarning();
  EXPECT_TRUE(contains(w, pgm.string() + ": frame 2 is listed in index.csv but its image is " +
                              std::to_string(whole.size() - 1) + " bytes, expected " +
                              std::to_string(whole.size()) +
                              " (its header and 64x48 pixels): "
                              "truncated; the session ends at frame 1"))
      << w;
  std::ofstream(pgm, std::ios::binary | std::ios::trunc) << "P5\n32 48\n255\n"
                                                         << std::string(32 * 48, 'x');
  EXPECT_TRUE(contains(firstWarning(), "its image is a 32x48 image, expected 64x48"));
  std::ofstream(pgm, std::ios::binary | std::ios::trunc) << "P6\n64 48\n255\n"
                                                         << std::string(64 * 48 * 3, 'x');
  EXPECT_TRUE(contains(firstWarning(), "its image is a P6 file, expected P5 (grey)"));
  std::ofstream(pgm, std::ios::binary | std::ios::trunc) << "P5\n64 48\n65535\n"
                                                         << std::string(64 * 48 * 2, 'x');
  EXPECT_TRUE(contains(firstWarning(), "has PNM maxval 65535, expected 255"));
  std::ofstream(pgm, std::ios::binary | std::ios::trunc) << "\x89PNG";
  EXPECT_TRUE(contains(firstWarning(), "its image is not a PNM file"));

  // Whole when opened, cut afterwards: the frame's read says so.
  std::ofstream(pgm, std::ios::binary | std::ios::trunc) << whole;
  const SessionReader reader(folder);
  ASSERT_EQ(reader.frameCount(), 3);
  truncateFile(pgm, whole.size() / 2);
  std::vector<CameraFrame> frames;
  try {
    reader.readFrame(2, frames);
    ADD_FAILURE() << "a cut image was read";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), pgm.string() + ": frame 2: is not a 64x48 bayer_rggb8 "
                                                  "image's header and pixels"))
        << e.what();
  }
  fs::remove_all(folder);
}

TEST(SessionReader, TornLastIndexLineIsSkippedWithAWarning) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("torn_index");
  writeSession(folder, rig, PixelFormat::kMono8, 5);
  // Cut mid-line: "4,133333349\n" loses its newline and two digits.
  truncateFile(folder / "index.csv", fs::file_size(folder / "index.csv") - 3);
  const SessionReader reader(folder);
  expectFramesExact(reader, PixelFormat::kMono8, 4);
  ASSERT_EQ(reader.warnings().size(), 1u) << allWarnings(reader);
  const std::string& w = reader.warnings()[0];
  EXPECT_TRUE(contains(w, "index.csv:6: torn last line '4,1333333")) << w;
  EXPECT_TRUE(contains(w, "the session ends at frame 3")) << w;
  fs::remove_all(folder);
}

// The disk fills in the middle of a frame's index line and room comes back before the recording
// ends (the operator frees some for the next take): the line is cut back, the file takes nothing
// more, and the session reads whole up to the frame before. (Buffered, the rest of the torn line
// was written out when the file closed, into a line that made the whole session unreadable.) The
// disk is filled by a file size limit, in a child process.
TEST(SessionReader, AFullDiskMidIndexLineLeavesTheFramesBeforeIt) {
  RingRigSpec spec;
  spec.cameras = 3;
  spec.width = 8;
  spec.height = 6;  // 59-byte PNM images: under the limit that the index reaches
  const Rig rig = makeRingRig(spec);
  const fs::path folder = freshFolder("full_index");
  const int result = testing::inChildProcess([&] {
    SessionWriter writer(folder, rig, PixelFormat::kMono8, 30.0, "test", {}, ImageFiles::kPnm);
    const auto write = [&](int64_t f) {
      try {
        writer.writeFrame(f, timestampOf(f), views(frameImages(rig, PixelFormat::kMono8, f)));
        return true;
      } catch (const Error&) {
        return false;
      }
    };
    for (int f = 0; f < 10; ++f) write(f);
    testing::limitFileSize(fs::file_size(folder / "index.csv") + 5);  // "10,333333347\n": 13
    if (write(10)) return 2;
    testing::limitFileSize(0);  // room again
    if (write(11)) return 3;
    return 0;
  });
  ASSERT_EQ(result, 0) << "2: frame 10 written past a full disk, 3: frame 11 after it";
  const SessionReader reader(folder);
  EXPECT_TRUE(reader.warnings().empty()) << allWarnings(reader);
  expectFramesExact(reader, PixelFormat::kMono8, 10);
  fs::remove_all(folder);
}

TEST(SessionReader, TruncatedLastImageAndLeftoverPartialFileEndTheSessionBeforeThem) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("torn_image");
  writeSession(folder, rig, PixelFormat::kRgb8, 5);
  const fs::path png = folder / "cam02" / "000004.png";
  truncateFile(png, fs::file_size(png) / 2);
  fs::copy_file(folder / "cam01" / "000003.png", folder / "cam01" / "000005.png.tmp-a1b2c3");
  const SessionReader reader(folder);
  expectFramesExact(reader, PixelFormat::kRgb8, 4);
  const std::string w = allWarnings(reader);
  ASSERT_EQ(reader.warnings().size(), 2u) << w;
  EXPECT_TRUE(contains(w, png.string() + ": frame 4 is listed in index.csv but its image is "
                                         "truncated"))
      << w;
  EXPECT_TRUE(contains(w, "the session ends at frame 3")) << w;
  EXPECT_TRUE(contains(w, "000005.png.tmp-a1b2c3: left over from an interrupted write; ignored"))
      << w;
  fs::remove_all(folder);
}

// A bad image at the end (a crash, a full disk) ends the session there; one before whole frames (a
// damaged file) leaves its frame out. It ended the session too, and a merged take lost every frame
// after it.
TEST(SessionReader, AMissingOrWrongImageLeavesItsFrameOutOrEndsTheSession) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("missing_image");
  writeSession(folder, rig, PixelFormat::kMono8, 5);
  fs::remove(folder / "cam03" / "000004.png");
  {
    const SessionReader reader(folder);
    expectFramesExact(reader, PixelFormat::kMono8, 4);
    ASSERT_EQ(reader.warnings().size(), 1u);
    EXPECT_TRUE(contains(reader.warnings()[0],
                         "000004.png: frame 4 is listed in index.csv but its "
                         "image is missing; the session ends at frame 3"))
        << reader.warnings()[0];
  }
  fs::remove(folder / "cam03" / "000002.png");
  {
    const SessionReader reader(folder);
    ASSERT_EQ(reader.frameCount(), 3);
    EXPECT_EQ(reader.frameId(0), 0);
    EXPECT_EQ(reader.frameId(1), 1);
    EXPECT_EQ(reader.frameId(2), 3);
    std::vector<CameraFrame> frames;
    reader.readFrame(2, frames);
    EXPECT_TRUE(frames[2].image.pixels == frameImages(rig, PixelFormat::kMono8, 3)[2].pixels);
    EXPECT_EQ(reader.timestampNs(2), timestampOf(3));
    ASSERT_EQ(reader.warnings().size(), 2u);
    EXPECT_TRUE(contains(allWarnings(reader),
                         "000002.png: frame 2 is listed in index.csv but its image is missing; "
                         "that frame is left out, the frames after it are whole"))
        << allWarnings(reader);
  }
  // An image of the wrong size, and one of the wrong channel count.
  cv::imwrite((folder / "cam03" / "000002.png").string(), cv::Mat(24, 32, CV_8UC1, cv::Scalar(0)));
  EXPECT_TRUE(contains(allWarnings(SessionReader(folder)), "is a 32x24 image, expected 64x48"));
  cv::imwrite((folder / "cam03" / "000002.png").string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(0)));
  EXPECT_TRUE(contains(allWarnings(SessionReader(folder)),
                       "PNG colour type 2, expected 8-bit grey (type 0)"));
  fs::remove_all(folder);
}

TEST(SessionReader, MalformedFilesAreErrorsNamingFileAndLine) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("malformed");
  writeSession(folder, rig, PixelFormat::kMono8, 3);
  const std::string yaml = (folder / "session.yaml").string();
  const std::string index = (folder / "index.csv").string();
  const std::string yaml_text = readFile(yaml), index_text = readFile(index);
  auto expectError = [&](const std::string& message) {
    try {
      SessionReader reader(folder);
      ADD_FAILURE() << "no error, expected: " << message;
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), message)) << e.what() << "\nexpected: " << message;
    }
    std::ofstream(yaml, std::ios::trunc) << yaml_text;
    std::ofstream(index, std::ios::trunc) << index_text;
  };
  replaceInFile(yaml, "pixel_format: mono8", "pixel_format: yuv422");
  expectError(yaml +
              ":7: pixel_format: expected one of mono8, bayer_rggb8, bayer_grbg8, bayer_gbrg8, "
              "bayer_bggr8, rgb8, got 'yuv422'");
  replaceInFile(yaml, "cameras: [cam01, cam02, cam03]", "cameras: [cam01, cam03, cam02]");
  expectError(yaml +
              ":9: cameras: expected the cameras of rig.yaml, in its order: [cam01, cam02, "
              "cam03], got [cam01, cam03, cam02]");
  replaceInFile(yaml, "cameras: [cam01, cam02, cam03]", "cameras: [cam01, cam02]");
  expectError(yaml + ":9: cameras: expected the cameras of rig.yaml");
  replaceInFile(yaml, "version: 1", "version: 2");
  expectError(yaml + ":3: version: this build reads version 1, got 2");
  replaceInFile(yaml, "format: lumistage-session", "format: lumistage-rig");
  expectError(yaml + ":2: format: expected lumistage-session, got 'lumistage-rig'");
  replaceInFile(yaml, "fps: 30", "fps: -30");
  expectError(yaml + ":6: fps: expected a frame rate above 0 and at most 1000, got -30");
  replaceInFile(yaml, "fps: 30", "fps: 1e10");  // a frame period of 0 ns: nodes divided by it
  expectError(yaml + ":6: fps: expected a frame rate above 0 and at most 1000, got 1e10");
  replaceInFile(yaml, "truth: false", "truth: false\nlens: wide");
  expectError(yaml + ":11: lens: unknown key 'lens'");
  replaceInFile(index, "1,", "x1,");
  expectError(index + ":3: expected frame,timestamp_ns as two whole numbers, got 'x1,33333350'");
  replaceInFile(index, "1,", "1,2,");
  expectError(index + ":3: expected frame,timestamp_ns as two whole numbers, got '1,2,33333350'");
  replaceInFile(index, "2,", "0,");
  expectError(index + ":4: frame 0 after frame 1: frame numbers must increase");
  replaceInFile(index, "frame,timestamp_ns", "frame;timestamp_ns");
  expectError(index + ":1: expected the header 'frame,timestamp_ns', got 'frame;timestamp_ns'");
  fs::remove_all(folder);
}

// A FIFO where a frame's image should be: fopen on it blocked `stream` for ever. In a child with an
// alarm, so that a regression fails instead of hanging.
TEST(SessionReader, AFifoInACameraFolderIsRefusedNotOpened) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("fifo");
  writeSession(folder, rig, PixelFormat::kMono8, 3);
  const fs::path image = folder / "cam02" / "000001.png";
  fs::remove(image);
  ASSERT_EQ(::mkfifo(image.c_str(), 0600), 0);
  const int code = testing::inChildProcess([&] {
    ::alarm(20);
    SessionReader reader(folder);
    const std::string warnings = allWarnings(reader);
    if (reader.frameCount() != 2) return 1;
    if (!contains(warnings, "cam02/000001.png")) return 2;
    if (!contains(warnings, "is not a regular file")) return 3;
    // Put there after the session was opened: the frame fails, it does not block.
    std::vector<CameraFrame> frames;
    ::unlink((folder / "cam01" / "000002.png").c_str());
    if (::mkfifo((folder / "cam01" / "000002.png").c_str(), 0600) != 0) return 4;
    try {
      reader.readFrame(1, frames);
      return 5;
    } catch (const Error& e) {
      if (!contains(e.what(), "is not a regular file")) return 6;
    }
    // session.yaml a FIFO: an Error, not a wait.
    fs::remove(folder / "session.yaml");
    if (::mkfifo((folder / "session.yaml").c_str(), 0600) != 0) return 7;
    const std::string m = testing::errorOf([&] { SessionReader again(folder); });
    return contains(m, "session.yaml: is not a regular file") ? 0 : 8;
  });
  EXPECT_EQ(code, 0);
  fs::remove_all(folder);
}

// A session.yaml whose rig is another kind of file (written by someone else, read by a user who
// may read more): the error says what is wrong, not what the file holds.
TEST(SessionReader, ARigThatIsAnotherKindOfFileIsNotEchoed) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("rig_passwd");
  writeSession(folder, rig, PixelFormat::kMono8, 1);
  const fs::path secret = folder / "passwd";
  std::ofstream(secret) << "root:x:0:0:root:/root:/bin/bash\nsecret: hunter2\n";
  replaceInFile(folder / "session.yaml", "rig: rig.yaml", "rig: " + secret.string());
  std::string m = testing::errorOf([&] { SessionReader reader(folder); });
  EXPECT_TRUE(contains(m, "passwd")) << m;
  EXPECT_FALSE(contains(m, "root:x")) << m;
  EXPECT_FALSE(contains(m, "hunter2")) << m;
  // A YAML map of another kind: its keys stay out too (the format is checked first).
  std::ofstream(secret, std::ios::trunc) << "password: hunter2\n";
  m = testing::errorOf([&] { SessionReader reader(folder); });
  EXPECT_TRUE(contains(m, "missing key 'format'")) << m;
  EXPECT_FALSE(contains(m, "password")) << m;
  fs::remove_all(folder);
}

// Times that go back (a camera whose clock restarted mid-take), below 0 or beyond 10 days: each
// is taken as the frame before's, with a warning naming the first, and every frame kept. A replay
// at the recorded rate replayed the rest at once, or waited for ever, or overflowed its clock.
TEST(SessionReader, TimesGoingBackOrAbsurdAreTheFrameBeforesAndSaid) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("times");
  writeSession(folder, rig, PixelFormat::kMono8, 4);
  const fs::path index = folder / "index.csv";
  std::ofstream(index, std::ios::trunc)
      << "frame,timestamp_ns\n0,0\n1,33333350\n2,1000\n3,999999999933333350\n";
  const SessionReader reader(folder);
  ASSERT_EQ(reader.frameCount(), 4);
  EXPECT_EQ(reader.timestampNs(2), 33333350);
  EXPECT_EQ(reader.timestampNs(3), 33333350);
  EXPECT_TRUE(contains(allWarnings(reader),
                       index.string() + ":4: frame 2 at 1000 ns, after 33333350 ns: 2 times going "
                                        "back, below 0 or beyond 10 days"))
      << allWarnings(reader);
  fs::remove_all(folder);
}

// A session whose masks were repaired (lumistage session masks) keeps the given ones in
// masks-given/: the reader opens it as before, serves the repaired masks as the session's and the
// given ones on asking.
TEST(SessionReader, ServesTheGivenMasksBesideTheRepairedOnes) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("given_masks");
  {
    SessionWriter writer(folder, rig, PixelFormat::kMono8, 30.0, "import");
    for (int f = 0; f < 2; ++f)
      writer.writeFrame(f, timestampOf(f), views(frameImages(rig, PixelFormat::kMono8, f)));
  }
  const cv::Mat given(48, 64, CV_8U, cv::Scalar(255)), repaired(48, 64, CV_8U, cv::Scalar(0));
  fs::create_directories(folder / "masks" / "cam02");
  cv::imwrite((folder / "masks" / "cam02" / "000001.png").string(), given);
  {
    const SessionReader reader(folder);
    EXPECT_TRUE(reader.hasMasks());
    EXPECT_FALSE(reader.hasRepairedMasks());
    EXPECT_EQ(reader.givenMaskPath(1, 1), folder / "masks" / "cam02" / "000001.png");
    EXPECT_EQ(reader.readGivenMask(1, 1), std::vector<uint8_t>(64 * 48, 255));
  }
  fs::rename(folder / "masks", folder / "masks-given");
  fs::create_directories(folder / "masks" / "cam02");
  cv::imwrite((folder / "masks" / "cam02" / "000001.png").string(), repaired);
  const SessionReader reader(folder);
  EXPECT_TRUE(reader.warnings().empty()) << allWarnings(reader);
  EXPECT_EQ(reader.frameCount(), 2);
  EXPECT_TRUE(reader.hasRepairedMasks());
  EXPECT_EQ(reader.readMask(1, 1), std::vector<uint8_t>(64 * 48, 0));
  EXPECT_EQ(reader.givenMaskPath(1, 1), folder / "masks-given" / "cam02" / "000001.png");
  EXPECT_EQ(reader.readGivenMask(1, 1), std::vector<uint8_t>(64 * 48, 255));
  try {
    reader.readGivenMask(0, 1);
    ADD_FAILURE() << "a missing given mask was read";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), (folder / "masks-given" / "cam01" / "000001.png").string() +
                                       ": cannot read the given mask (64x48 PNG, camera cam01)"))
        << e.what();
  }
  fs::remove_all(folder);
}

// The empty stage filmed before the take (a stage without a green screen is keyed on it): written
// beside the frames, not in the index, read back bit-exact per camera; a damaged plate file is an
// error naming it.
TEST(SessionReader, ReadsBackThePlateOfTheEmptyStage) {
  const Rig rig = smallRig();
  for (const ImageFiles files : {ImageFiles::kPng, ImageFiles::kPnm}) {
    const fs::path folder = freshFolder("plate");
    {
      SessionWriter writer(folder, rig, PixelFormat::kBayerRggb8, 30.0, "test", {}, files);
      for (int f = 0; f < 3; ++f)
        writer.writePlate(f, views(frameImages(rig, PixelFormat::kBayerRggb8, 10 + f)));
      for (int f = 0; f < 2; ++f) {
        writer.writeFrame(f, timestampOf(f), views(frameImages(rig, PixelFormat::kBayerRggb8, f)));
      }
      // A plate frame of another size is refused, naming it.
      std::vector<Image> wrong = frameImages(rig, PixelFormat::kMono8, 0);
      try {
        writer.writePlate(3, views(wrong));
        ADD_FAILURE() << "a plate of another format was written";
      } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "plate frame 3, camera cam01: got a 64x48 mono8 image"))
            << e.what();
      }
    }
    const SessionReader reader(folder);
    EXPECT_TRUE(reader.warnings().empty()) << allWarnings(reader);
    EXPECT_EQ(reader.frameCount(), 2);  // the plate is no frame of the session
    for (int c = 0; c < rig.cameraCount(); ++c) {
      ASSERT_EQ(reader.plateFrames(c), 3);
      for (int f = 0; f < 3; ++f) {
        EXPECT_TRUE(reader.readPlate(c, f).pixels ==
                    frameImages(rig, PixelFormat::kBayerRggb8, 10 + f)[c].pixels)
            << "camera " << c << " plate frame " << f;
      }
    }
    // Damaged after the session was written: an error naming the file.
    const fs::path damaged = reader.platePath(1, 2);
    std::ofstream(damaged, std::ios::trunc) << "not an image";
    try {
      reader.readPlate(1, 2);
      ADD_FAILURE() << "a damaged plate frame was read";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "the empty stage's " + damaged.string())) << e.what();
    }
    fs::remove_all(folder);
  }
  // A session without a plate: none.
  const fs::path folder = freshFolder("no_plate");
  writeSession(folder, rig, PixelFormat::kMono8, 1);
  EXPECT_EQ(SessionReader(folder).plateFrames(0), 0);
  fs::remove_all(folder);
}

TEST(SessionReader, ReadsGroundTruthJointsAndMaskPaths) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("truth");
  const std::vector<std::string> names = {"pelvis", "head"};
  std::vector<std::vector<Eigen::Vector3d>> joints;
  {
    SessionWriter writer(folder, rig, PixelFormat::kMono8, 30.0, "virtual-studio", names);
    std::vector<std::vector<uint8_t>> masks(3, std::vector<uint8_t>(64 * 48, 255));
    for (int f = 0; f < 3; ++f) {
      FrameTruth truth;
      truth.joints = {Eigen::Vector3d(0.1 * f, 1.0 / 3.0, 1e-17), Eigen::Vector3d(-f, 2, 1.75)};
      truth.masks = &masks;
      joints.push_back(truth.joints);
      writer.writeFrame(f, timestampOf(f), views(frameImages(rig, PixelFormat::kMono8, f)), &truth);
    }
  }
  const SessionReader reader(folder);
  EXPECT_TRUE(reader.hasTruth());
  std::vector<std::string> read_names;
  const std::vector<std::vector<Eigen::Vector3d>> read = reader.readTruthJoints(&read_names);
  EXPECT_EQ(read_names, names);
  ASSERT_EQ(read.size(), 3u);
  for (int f = 0; f < 3; ++f) {
    for (int j = 0; j < 2; ++j) EXPECT_TRUE(read[f][j] == joints[f][j]) << f << " " << j;  // exact
  }
  EXPECT_TRUE(fs::exists(reader.truthMaskPath(1, 2)));
  EXPECT_EQ(reader.truthMaskPath(1, 2), folder / "truth" / "masks" / "cam02" / "000002.png");
  // A joint that is not a number is an error naming the file and line, not NaN scores.
  const std::string csv = (folder / "truth" / "joints.csv").string();
  const std::string text = readFile(csv);
  const size_t line3 = text.find('\n', text.find('\n') + 1) + 1;  // frame 1's line
  const size_t comma = text.find(',', line3);
  std::ofstream(csv, std::ios::trunc)
      << text.substr(0, comma + 1) << "nan" << text.substr(text.find(',', comma + 1));
  try {
    reader.readTruthJoints();
    ADD_FAILURE() << "a NaN joint was read";
  } catch (const Error& e) {
    EXPECT_TRUE(contains(e.what(), csv + ":3: expected a frame number and 6 numbers")) << e.what();
  }
  fs::remove_all(folder);
}

// A virtual studio's session merged alone (made PNM, or its cameras put in a rig's order) keeps its
// ground truth, frame for frame: eval runs on it as on the original.
TEST(SessionReader, ASessionMergedAloneKeepsItsGroundTruth) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("merged_truth");
  const std::vector<std::string> names = {"pelvis", "head"};
  {
    SessionWriter writer(folder / "filmed", rig, PixelFormat::kMono8, 30.0, "virtual-studio",
                         names);
    std::vector<std::vector<uint8_t>> masks(3, std::vector<uint8_t>(64 * 48, 0));
    TriangleMesh surface;
    surface.positions.resize(3, 3);
    surface.positions << 0, 1, 0, 0, 0, 1, 0, 0, 0.5f;
    surface.triangles = {Eigen::Vector3i(0, 1, 2)};
    for (int f = 0; f < 3; ++f) {
      masks[1][size_t(f)] = 255;  // a different pixel of camera 2's mask each frame
      surface.positions(2, 2) = float(f);
      FrameTruth truth{
          {Eigen::Vector3d(0.1 * f, 1, 2), Eigen::Vector3d(-f, 2, 1.75)}, &surface, &masks};
      writer.writeFrame(10 + f, timestampOf(f), views(frameImages(rig, PixelFormat::kMono8, f)),
                        &truth);
    }
  }
  const SessionReader filmed(folder / "filmed");
  mergeTake({folder / "filmed"}, folder / "pnm", {}, ImageFiles::kPnm);
  const SessionReader merged(folder / "pnm");
  ASSERT_TRUE(merged.hasTruth());
  ASSERT_EQ(merged.frameCount(), 3);
  std::vector<std::string> read_names;
  EXPECT_EQ(merged.readTruthJoints(&read_names), filmed.readTruthJoints());
  EXPECT_EQ(read_names, names);
  for (int f = 0; f < 3; ++f) {
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(merged.readTruthMask(c, f), filmed.readTruthMask(c, f)) << f << " " << c;
    const std::string ply = fmt::format("truth/surface/{:06}.ply", 10 + f);
    EXPECT_EQ(readPlyMesh(folder / "pnm" / ply).positions(2, 2), float(f));
  }
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
