// libFuzzer target over decodeMessage(), the one place network bytes become data, and over the
// decoding of the refinement statistics a message carries (packed or zstd-compressed), which the
// studio does next. Any input must give a message or a reason, never a crash, a hang or a read
// out of bounds (AddressSanitizer).
// With LUMISTAGE_FUZZ_SEED_DIR set, it first writes one valid message of each kind there, so the
// fuzzer starts from inputs that pass the verifier and explores the checks behind it.
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/imaging/partial_image_codec.h"
#include "core/net/message_codec.h"
#include "core/refine/refinement_statistics.h"

namespace {

using namespace lumistage;

void writeSeeds(const std::string& dir) {
  std::vector<MessageBody> bodies;
  bodies.push_back(HelloData{"node1", {"cam01", "cam02", "cam03"}, kProtocolVersion, {"rle"}});
  bodies.push_back(
      HeartbeatData{{{"cam01", 100, 1, 30.f, ""}, {"cam02", 99, 2, 29.f, "late"}}, 4096, 0.5f});
  bodies.push_back(SilhouettesData{{{0, 12, 5, std::vector<uint8_t>(8, 0x3c)}}});
  bodies.push_back(PoseData{{0, 0, 1}, std::vector<float>(9, 0.25f)});
  VertexStatisticsData stats;
  stats.vertex_count = 2;
  stats.offset_count = 3;
  stats.packed = {2, 0, 0, 0, 3, 6, 1, 2, 0x20, 0x01, 0, 0, 0x10, 0, 4, 5, 6, 9, 9, 9, 200, 1};
  bodies.push_back(stats);
  RefinementStatistics small;  // the compressed form of a few samples with colour
  small.reset(3, 4, 6);
  for (int s = 0; s < small.sampleCount(); ++s) {
    small.colour_count[s] = uint8_t(s % 3);
    for (int c = 0; c < 3; ++c) small.sums[3 * s + c] = uint16_t(small.colour_count[s] * (10 + c));
    small.squares[s] = uint32_t(small.colour_count[s] * 400);
  }
  stats.vertex_count = 3;
  stats.offset_count = 4;
  RefinementStatisticsCodec().encode(small, stats.packed);
  bodies.push_back(stats);
  bodies.push_back(OffsetsData{21, {0, 5, 20}, {7, 0, 0xffff}});
  bodies.push_back(
      ViewData{0, 320, 240, 300, 300, 160, 120, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 3}});
  const std::vector<uint8_t> rgba(4 * 3 * 4, 9);
  bodies.push_back(PartialImageData{0, 4, 3, ImageEncoding::kRawRgba, rgba});
  bodies.push_back(PartialImageData{0, 4, 3, ImageEncoding::kRleRgba, encodeRleRgba(rgba)});
  bodies.push_back(FrameTimestampsData{{{"capture", 1}, {"sent", 2}}});
  bodies.push_back(RecordData{"take-1", 10, 20});
  HeartbeatData recording;
  recording.take = {"take-1", 10, 20, 5, 1, 4096, false, "", 123456789, "node1-pc:1"};
  bodies.push_back(recording);
  for (size_t i = 0; i < bodies.size(); ++i) {
    Message m;
    m.sender = "node1";
    m.frame_id = static_cast<int64_t>(i);
    m.body = bodies[i];
    const std::vector<uint8_t> bytes = encodeMessage(m);
    std::ofstream(dir + "/seed" + std::to_string(i), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("LUMISTAGE_FUZZ_SEED_DIR")) writeSeeds(dir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  lumistage::MessageLimits limits;
  limits.max_cameras = 9;  // small limits reach the count checks with small inputs
  limits.max_vertices = 5000;
  const lumistage::DecodeResult result = lumistage::decodeMessage(data, size, limits);
  if (result.ok() == !result.error().empty()) std::abort();  // exactly one of the two
  const auto* stats =
      result.ok() ? std::get_if<lumistage::VertexStatisticsData>(&result.message->body) : nullptr;
  if (stats) {
    // As the studio: decode (checked against the message's counts) and add.
    static lumistage::RefinementStatisticsCodec codec;
    static lumistage::RefinementStatistics decoded, sum;
    const lumistage::Status decoded_status =
        codec.decode(stats->packed, decoded, int(stats->vertex_count) * stats->offset_count);
    const bool ok = decoded_status.ok();
    if (ok == !decoded_status.error().empty()) std::abort();
    sum.reset(int(stats->vertex_count), stats->offset_count, ok ? decoded.colour_bits : 6);
    const lumistage::Status added = codec.add(stats->packed, sum);
    if (added.ok() == !added.error().empty() || (ok && !added.ok())) std::abort();
  }
  return 0;
}
