// Micro-benchmarks of the camera model's hot paths. Run: ./studio bench
#include <benchmark/benchmark.h>

#include <random>

#include "core/geometry/ring_rig.h"

namespace {

// The refinement's load: 2000 vertices x 21 offsets, ~42k points per camera, 12 cameras ~ 500k.
template <typename Scalar>
void projectBatch(benchmark::State& state) {
  const lumistage::Rig rig = lumistage::makeRingRig({});
  const lumistage::Camera& camera = rig.camera(0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<Scalar> u(-0.5, 0.5);
  const int n = static_cast<int>(state.range(0));
  Eigen::Matrix<Scalar, 3, Eigen::Dynamic> points(3, n);
  for (int i = 0; i < n; ++i) points.col(i) << u(rng), u(rng), 1 + 2 * u(rng);
  Eigen::Matrix<Scalar, 2, Eigen::Dynamic> pixels;
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> depths;
  for (auto _ : state) {
    camera.project(points, pixels, depths);
    benchmark::DoNotOptimize(pixels.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(projectBatch<float>)->Arg(42000)->Arg(504000)->Unit(benchmark::kMicrosecond);
BENCHMARK(projectBatch<double>)->Arg(42000)->Arg(504000)->Unit(benchmark::kMicrosecond);

void unprojectPixel(benchmark::State& state) {
  const lumistage::Rig rig = lumistage::makeRingRig({});
  const lumistage::Camera& camera = rig.camera(0);
  Eigen::Vector2d pixel(17.0, 23.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(camera.unproject(pixel));
    pixel.x() = pixel.x() > 1000 ? 17.0 : pixel.x() + 3.1;
  }
}
BENCHMARK(unprojectPixel);

}  // namespace
