// The calibration's costs: the wand solve against the number of samples (12 cameras, 0.3 px
// noise, 5% outliers) and the detector on a 1024x768 frame of the dark stage.
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/calib/wand_calibration.h"
#include "core/calib/wand_detector.h"
#include "core/calib/wand_simulation.h"
#include "core/geometry/ring_rig.h"

namespace lumistage {
namespace {

void BM_WandSolve(benchmark::State& state) {
  const Rig truth = makeRingRig(RingRigSpec{});
  WandSimulationOptions sim;
  sim.samples = static_cast<int>(state.range(0));
  const SimulatedWandSession session = simulateWandSession(truth, sim);
  for (auto _ : state) {
    const WandCalibrationResult result = calibrateWand(session.session, WandCalibrationOptions{});
    benchmark::DoNotOptimize(result.report.rms_px);
  }
}
BENCHMARK(BM_WandSolve)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_WandDetect(benchmark::State& state) {
  Image image;
  image.resize(PixelFormat::kMono8, 1024, 768);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = static_cast<uint8_t>(8 + i % 7);
  for (int y = 370; y < 390; ++y) {
    for (int x = 500; x < 520; ++x) {
      const double d2 = (x - 510.3) * (x - 510.3) + (y - 380.6) * (y - 380.6);
      image.pixels[static_cast<size_t>(y) * 1024 + x] +=
          static_cast<uint8_t>(240 * std::exp(-d2 / 8));
    }
  }
  WandDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image.view()));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WandDetect)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace lumistage
