// Every frame's work, once it has seen a frame of its size, allocates nothing (../shared/DESIGN.md:
// the hot paths are allocation-free). This binary replaces malloc and its kin (glibc lets a program
// do so) with counting wrappers around glibc's own, so that every allocation on the calling thread
// counts: operator new, Eigen's dynamic matrices, zstd's contexts, std::vector growth alike. A
// frame of the reference virtual studio goes through each stage twice; the second time must not
// allocate.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <malloc.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>

#include "core/body/human_skeleton.h"
#include "core/imaging/partial_image_codec.h"
#include "core/imaging/silhouettes.h"
#include "core/live/video_feed.h"
#include "core/live/vmc_sender.h"
#include "core/net/posed_body.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_sampler.h"
#include "core/refine/refinement_statistics.h"
#include "core/render/partial_image_blender.h"
#include "core/render/phong_subdivision.h"
#include "core/render/vertex_visibility.h"
#include "core/tracking/pose_tracker.h"
#include "tests/core/refine/reference_frame.h"

extern "C" {
void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* pointer, size_t size);
void* __libc_memalign(size_t alignment, size_t size);
void __libc_free(void* pointer);
}

namespace {
// Local to the executable: no allocation to reach them.
thread_local bool counting = false;
thread_local long allocations = 0;
void count() {
  if (counting) ++allocations;
}
}  // namespace

extern "C" {
void* malloc(size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(size_t count_, size_t size) {
  count();
  return __libc_calloc(count_, size);
}
void* realloc(void* pointer, size_t size) {
  count();
  return __libc_realloc(pointer, size);
}
void free(void* pointer) {
  __libc_free(pointer);
}
void* memalign(size_t alignment, size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(size_t alignment, size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, size_t alignment, size_t size) {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  count();
  void* p = __libc_memalign(alignment, size);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
void* valloc(size_t size) {
  count();
  return __libc_memalign(size_t(sysconf(_SC_PAGESIZE)), size);
}
void* pvalloc(size_t size) {
  count();
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  const size_t rounded = size == 0 ? page : (size + page - 1) / page * page;
  return rounded < size ? nullptr : __libc_memalign(page, rounded);
}
}

namespace lumistage {
namespace {

// Allocations on this thread while it lives.
class Allocations {
 public:
  Allocations() {
    allocations = 0;
    counting = true;
  }
  ~Allocations() { counting = false; }
  long stop() {
    counting = false;
    return allocations;
  }
};

// The reference studio's frame 20, its keyers learnt from it.
using Frame = testing::ReferenceFrame;

const Frame& frame() {
  static const Frame f(true);
  return f;
}

// Where the count test's allocations go, so that no compiler elides them.
void* volatile sink = nullptr;

// The count itself: what operator new, a growing vector and Eigen's dynamic matrices take.
TEST(HotPaths, AllocationsAreCounted) {
  Allocations allocations;
  auto one = std::make_unique<int>(1);
  sink = one.get();
  std::vector<int> grown;
  for (int i = 0; i < 3; ++i) {
    grown.push_back(i);  // 1, 2, 4
    sink = grown.data();
  }
  Eigen::MatrixXd matrix(20, 20);
  sink = matrix.data();
  const long counted = allocations.stop();
  EXPECT_EQ(counted, 5);
  EXPECT_EQ(*one + grown[2] + int(matrix.rows()), 23);
}

// A node's frame: the silhouettes, the body posed from the studio's pose message, the statistics
// sampled and compressed, the refined mesh, its curved surface, the partial image's wire form.
TEST(HotPaths, ANodesFrameAllocatesNothingAfterTheFirst) {
  const Frame& f = frame();
  const RefineConfig& refine = f.config.refine;
  std::vector<LowResSilhouette> silhouettes(3);
  RefinementSampler sampler(refine);
  RefinementStatistics stats;
  RefinementStatisticsCodec codec;
  std::vector<uint8_t> wire, mask, runs;
  const PoseData message =
      poseMessageFor(f.generic.skeleton, f.generic.skeleton, f.fit.pose, f.frame.joints);
  Pose pose;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals, refined;
  const std::vector<uint8_t> offsets(f.generic.rest.vertexCount(), uint8_t(refine.zeroLevel()));
  PhongSubdivision phong;
  std::vector<CameraMask> visible(f.generic.rest.vertexCount(), 0x0fff);
  std::vector<uint8_t> rgba(size_t(640) * 480 * 4, 0);
  for (size_t i = 0; i < rgba.size(); i += 4 * 7) rgba[i + 3] = 255;
  const std::vector<SamplerCamera> cameras = f.camerasOf(0);
  const auto nodeFrame = [&] {
    for (int k = 0; k < 3; ++k) {
      const int c = f.config.rig.nodes()[0].cameras[k];
      computeSilhouette(f.keyers[c], f.images[c].view(), c, kMaskStep, silhouettes[k]);
      silhouetteMask(silhouettes[k], mask);
    }
    posedBodyMesh(f.generic, message, pose, transforms, positions, normals);
    sampler.sample(cameras, positions, normals, f.generic.rest.triangles, stats);
    codec.encode(stats, wire);
    applyOffsets(refine, offsets, positions, normals, refined);
    phong.subdivide(refined, normals, f.generic.rest.triangles, visible);
    encodeAlphaRuns(rgba, runs);
  };
  nodeFrame();
  Allocations allocations;
  nodeFrame();
  EXPECT_EQ(allocations.stop(), 0);
  EXPECT_GT(wire.size(), 1000u);  // it did the work
}

// A node's frame keyed from another tool's masks (a stage without a green screen): the silhouettes
// and the renderer's masks from the masks, the statistics sampled with a key made over each
// frame's mask.
TEST(HotPaths, ANodesFrameKeyedFromMasksAllocatesNothingAfterTheFirst) {
  const Frame& f = frame();
  RefinementSampler sampler(f.config.refine);
  RefinementStatistics stats;
  std::vector<LowResSilhouette> silhouettes(3);
  std::vector<uint8_t> mask;
  std::vector<MaskKey> keys(3);
  std::vector<SamplerCamera> cameras = f.camerasOf(0);
  const auto nodeFrame = [&] {
    for (int k = 0; k < 3; ++k) {
      const int c = f.config.rig.nodes()[0].cameras[k];
      const Image& image = f.images[c];
      const std::vector<uint8_t>& actor = f.frame.masks[c];
      maskSilhouette(actor.data(), image.width, image.height, c, kMaskStep, silhouettes[k]);
      silhouetteMask(silhouettes[k], mask);
      keys[k] = MaskKey(actor.data(), image.width, image.height, isBayer(image.format));
      cameras[k].green_screen = nullptr;
      cameras[k].mask = &keys[k];
    }
    sampler.sample(cameras, f.positions, f.normals, f.generic.rest.triangles, stats);
  };
  nodeFrame();
  Allocations allocations;
  nodeFrame();
  EXPECT_EQ(allocations.stop(), 0);
  for (uint8_t nobody : sampler.seesNobody()) EXPECT_EQ(nobody, 0);  // it did the work
  EXPECT_GT(std::count_if(stats.colour_count.begin(), stats.colour_count.end(),
                          [](uint8_t n) { return n > 0; }),
            1000);
}

// The studio's frame: the nodes' statistics combined, the offsets chosen, which cameras see each
// vertex of the refined mesh, four partial images blended from their wire form.
TEST(HotPaths, TheStudiosFrameAllocatesNothingAfterTheFirst) {
  const Frame& f = frame();
  const RefineConfig& refine = f.config.refine;
  std::vector<std::vector<uint8_t>> wire(f.config.rig.nodeCount());
  {
    RefinementSampler sampler(refine);
    RefinementStatistics stats;
    RefinementStatisticsCodec codec;
    for (int n = 0; n < f.config.rig.nodeCount(); ++n) {
      sampler.sample(f.camerasOf(n), f.positions, f.normals, f.generic.rest.triangles, stats);
      codec.encode(stats, wire[n]);
    }
  }
  const PoseData message =
      poseMessageFor(f.generic.skeleton, f.generic.skeleton, f.fit.pose, f.frame.joints);
  Pose pose;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  RefinementStatisticsCodec codec;
  RefinementStatistics combined;
  MeshRefiner refiner(refine, f.generic.rest.vertexCount(), f.generic.rest.triangles);
  std::vector<uint8_t> offsets, blended;
  Eigen::Matrix3Xf refined;
  VertexVisibility visibility;
  PartialImageBlender blender;
  std::vector<uint8_t> rgba(size_t(640) * 480 * 4, 0), runs;
  for (size_t i = 0; i < rgba.size(); i += 4 * 5) rgba[i] = 200, rgba[i + 3] = 128;
  encodeAlphaRuns(rgba, runs);
  bool ok = true;
  const auto studioFrame = [&] {
    combined.reset(refine.pointsPerVertex() * f.generic.rest.vertexCount(), refine.offset_count,
                   refine.colour_bits);
    for (const auto& w : wire) ok = codec.add(w, combined).ok() && ok;
    combined.dropOutside();
    ok = refiner.refine(combined, offsets) && ok;
    posedBodyMesh(f.generic, message, pose, transforms, positions, normals);
    applyOffsets(refine, offsets, positions, normals, refined);
    visibility.compute(f.config.rig, refined, f.generic.rest.triangles, 4, 0.03);
    blender.reset(640, 480);
    for (int n = 0; n < 4; ++n) ok = blender.addAlphaRuns(runs) && ok;
    blender.finish(blended);
  };
  studioFrame();
  Allocations allocations;
  studioFrame();
  EXPECT_EQ(allocations.stop(), 0);
  EXPECT_TRUE(ok);
}

// Motion capture: the skeleton tracked from the 12 cameras' silhouettes, once calibrated.
TEST(HotPaths, TrackingAFrameAllocatesNothingAfterTheFirst) {
  const Frame& f = frame();
  std::vector<LowResSilhouette> silhouettes(f.config.rig.cameraCount());
  std::vector<const LowResSilhouette*> given;
  for (int c = 0; c < f.config.rig.cameraCount(); ++c) {
    computeSilhouette(f.keyers[c], f.images[c].view(), c, kMaskStep, silhouettes[c]);
    given.push_back(&silhouettes[c]);
  }
  PoseTracker tracker(f.config.rig, f.generic);
  for (int i = 0; i < 3; ++i) tracker.track(given);  // found, calibrated, tracked
  ASSERT_TRUE(tracker.track(given).valid());
  Allocations allocations;
  tracker.track(given);
  EXPECT_EQ(allocations.stop(), 0);
}

// The live skeleton: a frame's VMC bundle made and sent (to a UDP socket of this test's on
// 127.0.0.1), its bundle and messages built once.
TEST(HotPaths, TheSkeletonsLiveBundleAllocatesNothingAfterTheFirst) {
  const int receiver = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof(address);
  ASSERT_EQ(::bind(receiver, reinterpret_cast<sockaddr*>(&address), size), 0);
  ASSERT_EQ(::getsockname(receiver, reinterpret_cast<sockaddr*>(&address), &size), 0);
  const Skeleton skeleton = makeHumanSkeleton();
  VmcSender sender({"127.0.0.1", ntohs(address.sin_port)}, skeleton);
  PoseData pose;
  pose.angles.assign(size_t(3) * skeleton.jointCount(), 0.1f);
  ASSERT_TRUE(sender.send(pose, true));
  pose.angles[5] = 0.3f;
  Allocations allocations;
  const bool sent = sender.send(pose, true);
  EXPECT_EQ(allocations.stop(), 0);
  EXPECT_TRUE(sent);
  ::close(receiver);
}

// The view's live feed: offer() copies the picture into a slot it keeps (the thread that encodes
// and sends allocates the encoder's packets on its own time). To a UDP port nobody listens on.
TEST(HotPaths, TheViewsLiveFeedTakesAPictureAllocatingNothing) {
  VideoFeed feed(parseFeedUrl("udp://127.0.0.1:9"), 320, 240, 30);
  const std::vector<uint8_t> rgba(size_t(320) * 240 * 4, 128);
  ASSERT_TRUE(feed.offer(320, 240, rgba));
  Allocations allocations;
  const bool offered = feed.offer(320, 240, rgba);
  EXPECT_EQ(allocations.stop(), 0);
  EXPECT_TRUE(offered);
}

}  // namespace
}  // namespace lumistage
