// Lumigraph rendering on this machine's OpenGL (Mesa llvmpipe without a GPU): a node's partial
// image (3 cameras of the reference rig) at 640x480 and 1920x1080, its parts, and the studio's
// side. Run: ./studio bench, or build/tests/bench/render_bench.
#include <benchmark/benchmark.h>

#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>

#include "core/base/resource_path.h"
#include "core/body/human_model.h"
#include "core/capture/image.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/message_codec.h"
#include "core/render/gl.h"
#include "core/render/lumigraph_renderer.h"
#include "core/render/partial_image_blender.h"
#include "core/render/video_file.h"
#include "core/render/view_recorder.h"
#include "core/sim/virtual_studio.h"

namespace {

using namespace lumistage;

// CPU time of the whole process (llvmpipe renders on its own threads), milliseconds: on a
// machine shared with other work, a steadier figure than the wall clock.
double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

struct Scene {
  std::unique_ptr<VirtualStudio> studio;
  StudioFrame frame;
  TriangleMesh generic;   // the generic human (~1930 vertices) standing where the actor is
  std::vector<int> node;  // the first node's cameras
  std::vector<Image> bayer;
};

Scene& scene() {
  static Scene* s = [] {
    auto* s = new Scene;
    s->studio = std::make_unique<VirtualStudio>(
        loadStudioConfig(resourcePath("studio/reference.yaml")), 12);
    s->studio->renderFrame(10, s->frame);
    s->frame.surface.computeNormals();
    s->node = s->studio->rig().nodes()[0].cameras;
    s->generic = loadGenericHuman().rest;
    const Eigen::Vector3f offset =
        s->frame.surface.positions.rowwise().mean() - s->generic.positions.rowwise().mean();
    s->generic.positions.colwise() += offset;
    for (int c : s->node) {
      s->bayer.emplace_back();
      const Camera& cam = s->studio->rig().camera(c);
      rgbaToImage(s->frame.images[c].data(), cam.width(), cam.height(), PixelFormat::kBayerRggb8,
                  s->bayer.back());
    }
    return s;
  }();
  return *s;
}

Camera viewOf(int width, int height) {
  const Eigen::Vector3d centre(-3.2, -3.2, 1.7), target(0, 0, 1.0);
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Matrix3d R;
  R.row(0) = x, R.row(1) = z.cross(x), R.row(2) = z;
  const double f = 1.4 * width / 2;  // about 70 degrees across
  return Camera("view", width, height, {f, f, width / 2.0 - 0.5, height / 2.0 - 0.5, 0}, {}, R,
                -R * centre);
}

// The node's images, Bayer (one byte a pixel) or RGBA.
void uploadNodeImages(LumigraphRenderer& r, bool bayer) {
  Scene& s = scene();
  for (size_t j = 0; j < s.node.size(); ++j) {
    if (bayer) {
      r.setImage(int(j), s.bayer[j].view());
    } else {
      const Camera& c = s.studio->rig().camera(s.node[j]);
      r.setImageRgba(int(j), s.frame.images[s.node[j]].data(), c.width(), c.height());
    }
  }
}

// A node's renderer: images RGBA (bayer 0), Bayer as their cells' colours (1) or demosaiced at full
// resolution (2); mesh 0 the truth surface, 1 the generic human; the generic human Phong-
// subdivided as the pipeline renders it (phong < 0), the finely tessellated truth as it is, unless
// `phong` says otherwise.
std::unique_ptr<LumigraphRenderer> nodeRenderer(int bayer, int mesh = 0, int divisor = 4,
                                                int phong = -1) {
  Scene& s = scene();
  LumigraphParams params;
  params.bayer_images = bayer == 2 ? LumigraphParams::BayerImages::kFullResolution
                                   : LumigraphParams::BayerImages::kCells;
  params.depth_map_divisor = divisor;  // the visibility maps at the cameras' size / divisor
  params.phong_subdivision = phong < 0 ? mesh != 0 : phong != 0;
  auto r = std::make_unique<LumigraphRenderer>(s.studio->rig(), s.node, params);
  const TriangleMesh& m = mesh == 0 ? s.frame.surface : s.generic;
  r->setMesh(m.positions, m.normals, m.triangles);
  uploadNodeImages(*r, bayer != 0);
  return r;
}

// The node's frame after upload: the view rendered and read back (same mesh).
void nodePartialImage(benchmark::State& state) {
  auto r = nodeRenderer(int(state.range(2)), int(state.range(3)));
  const Camera view = viewOf(int(state.range(0)), int(state.range(1)));
  std::vector<uint8_t> rgba;
  r->render(view, rgba);
  const double cpu = processCpuMs();
  for (auto _ : state) {
    r->render(view, rgba);
    benchmark::DoNotOptimize(rgba.data());
  }
  state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
}
BENCHMARK(nodePartialImage)
    ->ArgNames({"w", "h", "bayer", "generic"})
    ->Args({640, 480, 0, 0})
    ->Args({640, 480, 1, 0})
    ->Args({640, 480, 0, 1})
    ->Args({640, 480, 1, 1})
    ->Args({640, 480, 2, 1})
    ->Args({1920, 1080, 0, 0})
    ->Args({1920, 1080, 1, 0})
    ->Args({1920, 1080, 0, 1})
    ->Args({1920, 1080, 1, 1})
    ->Args({1920, 1080, 2, 1})
    ->Unit(benchmark::kMillisecond);

// A new mesh before the view: with its visibility computed by the renderer (the rig's 12 maps at
// the cameras' size / divisor, as the single-process renderer does), or (divisor 0) given, as the
// studio sends it to the nodes.
void nodeMeshAndPartialImage(benchmark::State& state) {
  Scene& s = scene();
  const TriangleMesh& m = state.range(0) ? s.generic : s.frame.surface;
  const int divisor = int(state.range(1));
  auto r = nodeRenderer(false, int(state.range(0)), divisor > 0 ? divisor : 4, int(state.range(2)));
  VertexVisibility given;
  given.compute(s.studio->rig(), m.positions, m.triangles, 4, r->params().depth_tolerance_m);
  const Camera view = viewOf(640, 480);
  std::vector<uint8_t> rgba;
  const double cpu = processCpuMs();
  for (auto _ : state) {
    if (divisor > 0) {
      r->setMesh(m.positions, m.normals, m.triangles);
    } else {
      r->setMesh(m.positions, m.normals, m.triangles, given.masks());
    }
    r->render(view, rgba);
    benchmark::DoNotOptimize(rgba.data());
  }
  state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
}
BENCHMARK(nodeMeshAndPartialImage)
    ->ArgNames({"generic", "divisor", "phong"})
    ->Args({0, 0, 0})
    ->Args({0, 4, 0})
    ->ArgsProduct({{1}, {0, 2, 4, 8}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// The studio's share: which of the 12 cameras see each vertex of the refined mesh, once a frame.
void vertexVisibility(benchmark::State& state) {
  Scene& s = scene();
  const TriangleMesh& m = state.range(0) ? s.generic : s.frame.surface;
  VertexVisibility visibility;
  for (auto _ : state) {
    visibility.compute(s.studio->rig(), m.positions, m.triangles, 4, 0.03f);
    benchmark::DoNotOptimize(visibility.masks().data());
  }
}
BENCHMARK(vertexVisibility)->ArgName("generic")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Uploading the node's 3 images of 1024x768: RGBA (4 bytes a pixel, bayer 0), Bayer as its cells'
// colours (1 byte a pixel, 1) or as the mosaic for the shader to demosaic (2, 1 byte a pixel).
void uploadImages(benchmark::State& state) {
  const int bayer = int(state.range(0));
  auto r = nodeRenderer(bayer);
  state.SetLabel(reinterpret_cast<const char*>(glGetString(GL_RENDERER)));  // which OpenGL
  const double cpu = processCpuMs();
  for (auto _ : state) {
    uploadNodeImages(*r, bayer != 0);
    glFinish();  // the uploads done
  }
  state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
}
BENCHMARK(uploadImages)->ArgNames({"bayer"})->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// Clones: the cost of each extra one.
void clones(benchmark::State& state) {
  auto r = nodeRenderer(false);
  const Camera view = viewOf(640, 480);
  std::vector<Eigen::Affine3f> set;
  for (int i = 0; i < state.range(0); ++i) {
    Eigen::Affine3f t = Eigen::Affine3f::Identity();
    t.translate(Eigen::Vector3f(0.9f * (i % 4) - 1.35f, 0.9f * (i / 4), 0));
    set.push_back(t);
  }
  std::vector<uint8_t> rgba;
  const double cpu = processCpuMs();
  for (auto _ : state) {
    r->render(view, set, rgba);
    benchmark::DoNotOptimize(rgba.data());
  }
  state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
}
BENCHMARK(clones)->ArgName("clones")->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond);

// The wire: encoding a node's 640x480 partial image, and the studio's blend of four.
void encodePartialImage(benchmark::State& state) {
  auto r = nodeRenderer(false);
  std::vector<uint8_t> rgba, out;
  r->render(viewOf(640, 480), rgba);
  for (auto _ : state) {
    encodeAlphaRuns(rgba, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["bytes"] = double(out.size());
  state.counters["rle_rgba_bytes"] = double(encodeRleRgba(rgba).size());  // the paper's RLE
  state.counters["raw_bytes"] = double(rgba.size());
}
BENCHMARK(encodePartialImage)->Unit(benchmark::kMicrosecond);

// The studio's blend of four nodes' 640x480 images: from the wire's alpha runs (arg 1, what the
// studio does) or decoded to whole images first (arg 0).
void blendFourPartialImages(benchmark::State& state) {
  const bool runs = state.range(0) == 1;
  auto r = nodeRenderer(false);
  std::vector<uint8_t> rgba, encoded, decoded, out;
  r->render(viewOf(640, 480), rgba);
  encodeAlphaRuns(rgba, encoded);
  PartialImageBlender blender;
  for (auto _ : state) {
    blender.reset(640, 480);
    for (int n = 0; n < 4; ++n) {
      if (runs) {
        blender.addAlphaRuns(encoded);
      } else {
        decodeAlphaRuns(encoded, 640 * 480, decoded);
        blender.add(decoded);
      }
    }
    blender.finish(out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(blendFourPartialImages)->ArgName("runs")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// 30 frames of a 640x480 view of the actor, each moved 6 px right of the one before (the rows
// wrap): encoders that predict from the last frame have motion to find, as in a take.
std::vector<std::vector<uint8_t>> movingView() {
  auto r = nodeRenderer(false);
  std::vector<uint8_t> rgba;
  r->render(viewOf(640, 480), rgba);
  std::vector<std::vector<uint8_t>> frames(30, std::vector<uint8_t>(rgba.size()));
  for (int k = 0; k < 30; ++k) {
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x)
        std::memcpy(&frames[k][(y * 640 + (x + 6 * k) % 640) * 4], &rgba[(y * 640 + x) * 4], 4);
    }
  }
  return frames;
}

// Recording the director's view: one 640x480 blended image appended to the video, as the
// pipeline's blended sink does (the time it holds the pipeline). mp4 0: Motion-JPEG AVI through
// OpenCV (as before H.264); 1: H.264 MP4 through FFmpeg (libx264 ultrafast, fragmented).
void recordView(benchmark::State& state) {
  const std::vector<std::vector<uint8_t>> frames = movingView();
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      (state.range(0) == 1 ? "render_bench.mp4" : "render_bench.avi");
  ViewRecorder recorder(file, 30);
  int64_t id = 0;
  const double cpu = processCpuMs();  // the encoder's own threads included
  for (auto _ : state) {
    recorder.add(id, 640, 480, frames[id % frames.size()]);
    ++id;
  }
  state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
  // The video takes its name once closed and read back whole (until then NAME.partial.avi).
  if (!recorder.close()) {
    state.SkipWithError(recorder.status().error().c_str());
    return;
  }
  state.counters["bytes_per_frame"] =
      double(std::filesystem::file_size(file)) / double(std::max<int64_t>(1, id));
  std::filesystem::remove(file);
}
BENCHMARK(recordView)->ArgName("mp4")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// lumistage render's writer: one 640x480 image into a video file through FFmpeg. mp4 1: H.264
// (libx264 veryfast, CRF 20); 0: Motion-JPEG AVI (FFmpeg's encoder).
void writeVideoFile(benchmark::State& state) {
  const std::vector<std::vector<uint8_t>> moving = movingView();
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      (state.range(0) == 1 ? "render_bench_file.mp4" : "render_bench_file.avi");
  int64_t frames = 0;
  {
    VideoFileWriter video(file, 640, 480, 30);
    const double cpu = processCpuMs();  // the encoder's own threads included
    for (auto _ : state) {
      video.write(moving[frames % moving.size()].data(), PixelOrder::kRgba);
      ++frames;
    }
    state.counters["process_cpu_ms"] = (processCpuMs() - cpu) / double(state.iterations());
    video.close();
  }
  state.counters["bytes_per_frame"] =
      double(std::filesystem::file_size(file)) / double(std::max<int64_t>(1, frames));
  std::filesystem::remove(file);
}
BENCHMARK(writeVideoFile)->ArgName("mp4")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
