// Micro-benchmarks of the body model: posing the generic human is done many times a frame by the
// tracker and once per frame per node. Run: ./studio bench
#include <benchmark/benchmark.h>

#include "core/body/human_model.h"
#include "core/body/motion_library.h"

namespace {

const lumistage::SkinnedMesh& genericHuman() {
  static const lumistage::SkinnedMesh mesh = lumistage::makeHumanModel();
  return mesh;
}

// Forward kinematics and skinning transforms of the 24-joint skeleton.
void skinningTransforms(benchmark::State& state) {
  const auto& human = genericHuman();
  const lumistage::MotionClip clip = lumistage::makeBuiltinClip("walk", human.skeleton, 30, 2);
  std::vector<Eigen::Affine3f> transforms;
  size_t f = 0;
  for (auto _ : state) {
    human.skeleton.skinningTransforms(clip.frames[f++ % clip.frames.size()], transforms);
    benchmark::DoNotOptimize(transforms.data());
  }
}
BENCHMARK(skinningTransforms);

// Linear blend skinning of the ~2000-vertex generic human, positions and normals.
void skinGenericHuman(benchmark::State& state) {
  const auto& human = genericHuman();
  const lumistage::MotionClip clip = lumistage::makeBuiltinClip("walk", human.skeleton, 30, 2);
  std::vector<Eigen::Affine3f> transforms;
  human.skeleton.skinningTransforms(clip.frames[20], transforms);
  Eigen::Matrix3Xf positions, normals;
  for (auto _ : state) {
    lumistage::skinMesh(human, transforms, positions, normals);
    benchmark::DoNotOptimize(positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * human.rest.vertexCount());
  state.counters["vertices"] = human.rest.vertexCount();
}
BENCHMARK(skinGenericHuman)->Unit(benchmark::kMicrosecond);

}  // namespace
