#include "core/capture/session_recorder.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "core/capture/session_reader.h"
#include "tests/core/capture/capture_test_util.h"

namespace lumistage {
namespace {

using namespace lumistage::test;

TEST(Recorder, DropsWhenTheQueueIsFullAndPushNeverWaitsForTheDisk) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("drops");
  const std::vector<Image> source = frameImages(rig, PixelFormat::kMono8, 0);
  SessionRecorder recorder(folder, rig, PixelFormat::kMono8, 30.0, "test", /*queue_capacity=*/1);
  constexpr int kPushes = 300;
  int accepted = 0;
  double slowest_ms = 0;
  for (int f = 0; f < kPushes; ++f) {
    std::vector<Image> images;
    if (!recorder.takeSpareImages(images)) images = source;
    for (size_t c = 0; c < images.size(); ++c) images[c].pixels = source[c].pixels;
    const auto start = std::chrono::steady_clock::now();
    accepted += recorder.push(f, timestampOf(f), std::move(images));
    slowest_ms =
        std::max(slowest_ms,
                 std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
  }
  recorder.stop();
  const RecorderStats stats = recorder.stats();
  EXPECT_GT(stats.dropped, 0);
  EXPECT_EQ(stats.written, accepted);
  EXPECT_EQ(stats.written + stats.dropped, kPushes);
  EXPECT_GT(stats.bytes, 0);
  EXPECT_FALSE(stats.failed);
  // A PNG write takes a millisecond or so; push only takes a lock (generous for a busy machine).
  EXPECT_LT(slowest_ms, 50.0);
  EXPECT_FALSE(recorder.push(kPushes, 0, frameImages(rig, PixelFormat::kMono8, 0)));
  EXPECT_EQ(recorder.stats().refused, 1);
  const SessionReader reader(folder);
  EXPECT_EQ(reader.frameCount(), accepted);
  EXPECT_TRUE(reader.warnings().empty());
  fs::remove_all(folder);
}

TEST(Recorder, ImagesThatDoNotFitAreDroppedAndTheRecordingGoesOn) {
  const Rig rig = smallRig();
  const fs::path folder = freshFolder("wrong_images");
  SessionRecorder recorder(folder, rig, PixelFormat::kMono8, 30.0, "test");
  EXPECT_FALSE(recorder.push(0, 0, frameImages(rig, PixelFormat::kRgb8, 0)));
  std::vector<Image> two = frameImages(rig, PixelFormat::kMono8, 0);
  two.pop_back();
  EXPECT_FALSE(recorder.push(1, 1, std::move(two)));
  EXPECT_TRUE(recorder.push(2, 2, frameImages(rig, PixelFormat::kMono8, 2)));
  recorder.stop();
  const RecorderStats stats = recorder.stats();
  EXPECT_EQ(stats.dropped, 2);
  EXPECT_EQ(stats.written, 1);
  EXPECT_NE(stats.last_error.find("frame 1: 2 images for 3 cameras"), std::string::npos)
      << stats.last_error;
  fs::remove_all(folder);
}

// Images whose PNGs are tiny, so that index.csv is the file to reach the size limit first.
std::vector<Image> fullDiskImages(const Rig& rig, int64_t frame_id) {
  std::vector<Image> images = frameImages(rig, PixelFormat::kMono8, frame_id);
  for (Image& image : images) std::fill(image.pixels.begin() + 8, image.pixels.end(), 0);
  return images;
}

// The child of FullDiskStopsCleanly...: a process whose files may not grow beyond a few hundred
// bytes, as on a full disk (writes fail with EFBIG). It runs when the test binary starts with
// LUMISTAGE_RECORDER_CHILD_FOLDER set, before GoogleTest, and exits: 0 when the recorder failed
// cleanly and refused what came after, 1 otherwise.
int recordUntilTheDiskIsFull(const char* folder) {
  const Rig rig = smallRig();
  SessionRecorder recorder(folder, rig, PixelFormat::kMono8, 30.0, "test", 64);
  std::signal(SIGXFSZ, SIG_IGN);
  const rlimit limit{400, 400};
  if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) return 1;
  for (int f = 0; f < 60; ++f) recorder.push(f, timestampOf(f), fullDiskImages(rig, f));
  recorder.stop();
  const RecorderStats stats = recorder.stats();
  std::printf("RECORDER written=%lld failed=%d error=%s\n", static_cast<long long>(stats.written),
              int(stats.failed), stats.last_error.c_str());
  const bool refused = !recorder.push(99, 0, fullDiskImages(rig, 99));
  return stats.failed && refused ? 0 : 1;
}

[[maybe_unused]] const int kRecorderChild = [] {
  if (const char* folder = std::getenv("LUMISTAGE_RECORDER_CHILD_FOLDER")) {
    std::fflush(stdout);
    const int code = recordUntilTheDiskIsFull(folder);
    std::fflush(stdout);
    std::_Exit(code);
  }
  return 0;
}();

TEST(Recorder, FullDiskStopsCleanlyAndTheSessionStaysReadable) {
  const fs::path folder = freshFolder("full_disk");
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string command =
      "LUMISTAGE_RECORDER_CHILD_FOLDER=" + folder.string() + " " + self + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_TRUE(pipe);
  std::string output;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = ::pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;
  long long written = -1;
  const size_t at = output.find("RECORDER written=");
  ASSERT_NE(at, std::string::npos) << output;
  std::sscanf(output.c_str() + at, "RECORDER written=%lld", &written);
  EXPECT_GE(written, 3) << output;  // the limit was reached some frames in
  EXPECT_LT(written, 60) << output;
  // The kept error names the file that could not grow.
  EXPECT_NE(output.find("failed=1 error=" + folder.string()), std::string::npos) << output;
  EXPECT_TRUE(output.find("index.csv") != std::string::npos ||
              output.find(".png") != std::string::npos)
      << output;

  const SessionReader reader(folder);
  ASSERT_EQ(reader.frameCount(), written);
  std::vector<CameraFrame> frames;
  for (int i = 0; i < reader.frameCount(); ++i) {
    ASSERT_EQ(reader.frameId(i), i);
    reader.readFrame(i, frames);
    const std::vector<Image> expected = fullDiskImages(reader.rig(), i);
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(frames[c].image.pixels == expected[c].pixels);
  }
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
