// Micro-benchmarks of the mesh refinement (the paper's §IV) on a frame of the virtual studio: the
// generic human posed to the actor's true joints, the reference rig's 1024x768 images.
//   node side:   depth maps + samples of 2000 vertices (and their window points: /window:3, the
//                default) x 21 offsets x its 3 cameras, compressed for the wire (target < 5 ms)
//   module side: decompress and combine 4 nodes' statistics, choose the offsets (target < 2 ms)
// Run: ./studio bench, or build/tests/bench/refine_bench
#include <benchmark/benchmark.h>

#include "core/base/resource_path.h"
#include "core/body/human_model.h"
#include "core/body/joint_pose_fit.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_sampler.h"
#include "core/refine/refinement_statistics.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/refine/reference_frame.h"

namespace {

using namespace lumistage;

struct Scene : testing::ReferenceFrame {
  // Per window points (1, 3) and node, compressed as nodes send it.
  std::vector<std::vector<uint8_t>> wire[4];
  // Per window points, the offsets the module chose from the nodes' statistics on the posed mesh
  // alone (a first frame): the surface the nodes see the frames after through, as in the pipeline
  // (RefinementSampler::sample's surface_levels), and the wire above is sampled through it.
  std::vector<uint8_t> surface[4];

  Scene() : ReferenceFrame(false) {
    RefinementStatistics stats, combined;
    RefinementStatisticsCodec codec;
    for (int points : {1, 3}) {
      const RefineConfig refine = refineConfig(points);
      RefinementSampler sampler(refine);
      combined.reset(points * generic.rest.vertexCount(), refine.offset_count, refine.colour_bits);
      for (int n = 0; n < config.rig.nodeCount(); ++n) {
        sampler.sample(camerasOf(n), positions, normals, generic.rest.triangles, stats);
        combined.add(stats);
      }
      MeshRefiner(refine, generic.rest.vertexCount(), generic.rest.triangles)
          .refine(combined, surface[points]);
      for (int n = 0; n < config.rig.nodeCount(); ++n) {
        sampler.sample(camerasOf(n), positions, normals, generic.rest.triangles, stats,
                       surface[points]);
        wire[points].emplace_back();
        codec.encode(stats, wire[points].back());
      }
    }
  }
  RefineConfig refineConfig(int window_points) const {
    RefineConfig c = config.refine;
    c.window_points = window_points;
    return c;
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

// One node's whole share: depth maps of its 3 cameras (of the surface an earlier frame was refined
// to), samples, the compressed wire form.
void refineNodeSide(benchmark::State& state) {
  const Scene& s = scene();
  RefinementSampler sampler(s.refineConfig(int(state.range(0))));
  RefinementStatistics stats;
  RefinementStatisticsCodec codec;
  std::vector<uint8_t> wire, packed;
  const std::vector<SamplerCamera> cameras = s.camerasOf(0);
  for (auto _ : state) {
    sampler.sample(cameras, s.positions, s.normals, s.generic.rest.triangles, stats,
                   s.surface[state.range(0)]);
    codec.encode(stats, wire);
    benchmark::DoNotOptimize(wire.data());
  }
  encodeRefinementStatistics(stats, packed);
  state.counters["bytes"] = double(wire.size());
  state.counters["packed_bytes"] = double(packed.size());
  state.counters["vertices"] = double(s.positions.cols());
}
BENCHMARK(refineNodeSide)->ArgName("window")->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

// The depth maps alone (3 cameras, 1/8 resolution).
// Depth maps of the posed generic human: the refinement's (a node's 3 cameras at its step) or
// the lumigraph's visibility maps on the CPU (all 12 cameras at a quarter of their size).
void refineDepthMaps(benchmark::State& state) {
  const Scene& s = scene();
  const bool lumigraph = state.range(0) == 1;
  std::vector<int> cameras = s.config.rig.nodes()[0].cameras;
  if (lumigraph) {
    cameras.clear();
    for (int c = 0; c < s.config.rig.cameraCount(); ++c) cameras.push_back(c);
  }
  DepthMap map;
  for (auto _ : state) {
    for (int c : cameras) {
      map.render(s.config.rig.camera(c), s.positions, s.generic.rest.triangles,
                 lumigraph ? 4 : s.config.refine.depth_map_step);
      benchmark::DoNotOptimize(map.depths().data());
    }
  }
}
BENCHMARK(refineDepthMaps)->ArgName("lumigraph")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The module: decompress the 4 nodes' statistics, combine, choose every vertex's offset.
void refineModuleSide(benchmark::State& state) {
  const Scene& s = scene();
  const int points = int(state.range(0));
  MeshRefiner refiner(s.config.refine, s.generic.rest.vertexCount(), s.generic.rest.triangles);
  RefinementStatistics combined;
  RefinementStatisticsCodec codec;
  std::vector<uint8_t> offsets;
  for (auto _ : state) {
    combined.reset(points * s.generic.rest.vertexCount(), s.config.refine.offset_count,
                   s.config.refine.colour_bits);
    for (const auto& w : s.wire[points]) benchmark::DoNotOptimize(codec.add(w, combined));
    combined.dropOutside();
    refiner.refine(combined, offsets);
    benchmark::DoNotOptimize(offsets.data());
  }
}
BENCHMARK(refineModuleSide)->ArgName("window")->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The module's choice alone (statistics already combined): data terms, smoothness, temporal.
void refineModuleChooseOnly(benchmark::State& state) {
  const Scene& s = scene();
  const int points = int(state.range(0));
  MeshRefiner refiner(s.config.refine, s.generic.rest.vertexCount(), s.generic.rest.triangles);
  RefinementStatistics combined, decoded;
  combined.reset(points * s.generic.rest.vertexCount(), s.config.refine.offset_count,
                 s.config.refine.colour_bits);
  for (const auto& w : s.wire[points]) {
    benchmark::DoNotOptimize(decodeRefinementStatistics(w, decoded));
    combined.add(decoded);
  }
  std::vector<uint8_t> offsets;
  for (auto _ : state) {
    refiner.refine(combined, offsets);
    benchmark::DoNotOptimize(offsets.data());
  }
}
BENCHMARK(refineModuleChooseOnly)->ArgName("window")->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

}  // namespace
