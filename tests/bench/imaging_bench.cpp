// Keying on demand: the cost per pixel asked about. Run: ./studio bench
#include <benchmark/benchmark.h>

#include <random>

#include "core/imaging/keyer.h"
#include "core/imaging/silhouettes.h"

namespace {

// A 1024x768 Bayer frame of green screen with a grey block in the middle.
lumistage::Image stageFrame() {
  lumistage::Image image;
  image.resize(lumistage::PixelFormat::kBayerRggb8, 1024, 768);
  std::mt19937 rng(3);
  for (int y = 0; y < 768; ++y) {
    for (int x = 0; x < 1024; ++x) {
      const bool actor = x > 400 && x < 600 && y > 200 && y < 700;
      const bool green = (x + y) % 2 == 1;
      image.pixels[size_t(y) * 1024 + x] =
          static_cast<uint8_t>((actor ? 120 : (green ? 150 : 45)) + rng() % 5);
    }
  }
  return image;
}

// A low-resolution silhouette (one sample every `step` pixels), as a node sends for tracking.
void lowResolutionSilhouette(benchmark::State& state) {
  const lumistage::Image image = stageFrame();
  const lumistage::GreenScreenKeyer keyer;
  const int step = static_cast<int>(state.range(0));
  std::vector<uint8_t> mask;
  for (auto _ : state) {
    lumistage::lowResSilhouette(keyer, image.view(), step, mask);
    benchmark::DoNotOptimize(mask.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(mask.size()));
}
BENCHMARK(lowResolutionSilhouette)->Arg(4)->Arg(8)->Unit(benchmark::kMicrosecond);

// The same packed into bits, as a node computes it (computeSilhouette), at the step state.range(0).
void keyNodeSilhouette(benchmark::State& state, const lumistage::Image& image) {
  const lumistage::GreenScreenKeyer keyer;
  lumistage::LowResSilhouette silhouette;
  for (auto _ : state) {
    lumistage::computeSilhouette(keyer, image.view(), 0, int(state.range(0)), silhouette);
    benchmark::DoNotOptimize(silhouette.bits.data());
  }
}

void nodeSilhouette(benchmark::State& state) {
  keyNodeSilhouette(state, stageFrame());
}
BENCHMARK(nodeSilhouette)->Arg(4)->Arg(8)->Unit(benchmark::kMicrosecond);

// The same on an RGB camera (recorded sessions of the virtual studio, the demo's).
void nodeSilhouetteRgb(benchmark::State& state) {
  const lumistage::Image bayer = stageFrame();
  lumistage::Image image;
  image.resize(lumistage::PixelFormat::kRgb8, bayer.width, bayer.height);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const lumistage::Rgb c = lumistage::colourAt(bayer.view(), x, y);
      uint8_t* p = &image.pixels[3 * (size_t(y) * image.width + x)];
      p[0] = uint8_t(c.r), p[1] = uint8_t(c.g), p[2] = uint8_t(c.b);
    }
  }
  keyNodeSilhouette(state, image);
}
BENCHMARK(nodeSilhouetteRgb)->Arg(4)->Arg(8)->Unit(benchmark::kMicrosecond);

// The same keyed on a clean plate (a stage without a green screen): the plate learnt from the frame
// with its block of actor painted over with the screen, as the empty stage.
void nodeSilhouettePlate(benchmark::State& state) {
  const lumistage::Image image = stageFrame();
  lumistage::Image empty = image;
  for (int y = 200; y < 700; ++y)
    for (int x = 400; x < 600; ++x) empty.pixels[size_t(y) * 1024 + x] = (x + y) % 2 ? 150 : 45;
  lumistage::BackgroundModel plate(1024, 768);
  plate.add(empty.view());
  plate.learn();
  lumistage::LowResSilhouette silhouette;
  for (auto _ : state) {
    lumistage::computeSilhouette(plate, image.view(), 0, int(state.range(0)), silhouette);
    benchmark::DoNotOptimize(silhouette.bits.data());
  }
}
BENCHMARK(nodeSilhouettePlate)->Arg(4)->Arg(8)->Unit(benchmark::kMicrosecond);

// A camera's screen measured again, as a node does for each camera once every 30 frames
// (CameraNode::checkScreens).
void measureScreen(benchmark::State& state) {
  const lumistage::Image image = stageFrame();
  for (auto _ : state) {
    lumistage::GreenScreenKeyer measured;
    benchmark::DoNotOptimize(measured.learnScreen(image.view()));
  }
}
BENCHMARK(measureScreen)->Unit(benchmark::kMicrosecond);

}  // namespace

#include "core/geometry/ring_rig.h"
#include "core/tracking/visual_hull_locator.h"

namespace {

// Carving the stage (6 cm voxels) with 12 silhouettes of 128x96 cells: the placeholder tracker's
// cost per frame.
void locateActor(benchmark::State& state) {
  const lumistage::Rig rig = lumistage::makeRingRig({});
  const lumistage::VisualHullLocator locator(rig, 8);
  std::vector<lumistage::LowResSilhouette> silhouettes(rig.cameraCount());
  std::vector<const lumistage::LowResSilhouette*> all;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    auto& s = silhouettes[c];
    s.camera = c, s.step = 8, s.width = 128, s.height = 96;
    s.bits.assign(size_t(16) * 96, 0);
    for (int y = 30; y < 80; ++y) {
      for (int x = 56; x < 72; ++x) s.set(x, y);
    }
    all.push_back(&s);
  }
  for (auto _ : state) benchmark::DoNotOptimize(locator.locate(all));
}
BENCHMARK(locateActor)->Unit(benchmark::kMillisecond);

}  // namespace

#include <algorithm>
#include <filesystem>

#include "core/capture/session_writer.h"

namespace {

// A node's part of a take: its three 1024x768 Bayer cameras' set written by SessionWriter, as
// TakeRecorder's writer thread does: as PNGs (arg 0: encoded in parallel, written to files) or
// as PNM (arg 1: the pixels as they are, what takes use). The frames carry sensor-like noise
// (+-8 levels), which is what the PNG encoder spends its time on.
void recordNodeSet(benchmark::State& state) {
  lumistage::RingRigSpec spec;
  spec.cameras = 3;
  const lumistage::Rig rig = lumistage::makeRingRig(spec);
  std::vector<lumistage::Image> images(3, stageFrame());
  std::mt19937 rng(5);
  for (lumistage::Image& image : images) {
    for (uint8_t& p : image.pixels)
      p = static_cast<uint8_t>(std::clamp(int(p) + int(rng() % 17) - 8, 0, 255));
  }
  std::vector<lumistage::ImageView> views;
  for (const lumistage::Image& image : images) views.push_back(image.view());
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / "lumistage_bench_record_node_set";
  std::filesystem::remove_all(folder);
  int64_t frame = 0;
  {
    lumistage::SessionWriter writer(
        folder, rig, lumistage::PixelFormat::kBayerRggb8, 25, "bench", {},
        state.range(0) == 1 ? lumistage::ImageFiles::kPnm : lumistage::ImageFiles::kPng);
    for (auto _ : state) {
      writer.writeFrame(frame, frame * 40'000'000, views);
      ++frame;
    }
    state.counters["MB_per_set"] =
        double(writer.bytesWritten()) / std::max<int64_t>(1, frame) / 1e6;
  }
  std::filesystem::remove_all(folder);
}
BENCHMARK(recordNodeSet)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
