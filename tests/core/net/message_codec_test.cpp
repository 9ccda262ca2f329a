#include "core/net/message_codec.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>

#include "core/imaging/partial_image_codec.h"

namespace lumistage {
namespace {

Message envelope(MessageBody body) {
  Message m;
  m.sender = "node2";
  m.frame_id = 1234;
  m.sent_ns = 987654321012;
  m.body = std::move(body);
  return m;
}

std::vector<Message> oneOfEach() {
  HelloData hello{"node2", {"cam04", "cam05", "cam06"}, kProtocolVersion, {"silhouettes", "rle"}};
  HeartbeatData heartbeat{
      {{"cam04", 1000, 3, 29.97f, "", kKeyedOnGreen},
       {"cam05", 998, 5, 30.f, "timeout", kKeyedFromMasks}},
      123456789,
      0.42f,
      {"take-7", 120, 480, 300, 2, 123456, false, "disk full", 987654321, "node2-pc:5f3a"}};
  RecordData record{"take-7", 120, 480};
  SilhouettesData silhouettes;
  // 0x5a: 4 cells of each byte; of the last byte's 3 cells, 1: 45 cells, 135 colour bytes.
  std::vector<uint8_t> colours(135);
  for (size_t i = 0; i < colours.size(); ++i) colours[i] = uint8_t(i * 11 + 3);
  silhouettes.masks.push_back({4, 13, 7, std::vector<uint8_t>((13 * 7 + 7) / 8, 0x5a), colours});
  silhouettes.masks.push_back({5, 8, 8, std::vector<uint8_t>(8, 0xff), {}});
  PoseData pose;
  pose.root[0] = 0.1f;
  pose.root[1] = -0.2f;
  pose.root[2] = 0.95f;
  pose.scale = 1.04f;
  for (int i = 0; i < 22 * 3; ++i) pose.angles.push_back(0.01f * static_cast<float>(i));
  VertexStatisticsData stats;
  stats.vertex_count = 5;
  stats.offset_count = 3;
  stats.packed = {5, 0, 0, 0, 3, 6, 1, 2};  // the header, then a byte a sample (no colour)
  for (int i = 0; i < 15; ++i) stats.packed.push_back(uint8_t(i % 3));
  stats.packed.push_back(0x05);  // the contour bits of the 5 vertices
  OffsetsData offsets{21, {0, 10, 20, 5, 7}, {0x0fff, 0, 0x8001, 3, 0xffff}};
  ViewData view{1,
                320,
                240,
                300.5f,
                301,
                159.5f,
                119.5f,
                {1, 0, 0, 0, 0, -1, 0, 1, 0},
                {0.1f, 1.2f, 4},
                {1.5f, -0.5f, 3.1f, -1.5f, 0.25f, 0}};  // two clones
  std::vector<uint8_t> rgba(6 * 4 * 4, 0);
  rgba[0] = 255;
  PartialImageData raw{1, 6, 4, ImageEncoding::kRawRgba, rgba};
  PartialImageData rle{1, 6, 4, ImageEncoding::kRleRgba, encodeRleRgba(rgba)};
  FrameTimestampsData stamps{{{"capture", 100}, {"silhouettes", 250}, {"sent", 300}}};
  std::vector<Message> all;
  for (MessageBody body :
       std::vector<MessageBody>{hello, heartbeat, silhouettes, pose, stats, offsets, raw, rle,
                                stamps, view, record, FrameIdsData{-123456}}) {
    all.push_back(envelope(std::move(body)));
  }
  return all;
}

std::string decodeError(const Message& m, const MessageLimits& limits = {}) {
  const std::vector<uint8_t> bytes = encodeMessage(m);
  const DecodeResult r = decodeMessage(bytes.data(), bytes.size(), limits);
  EXPECT_FALSE(r.ok()) << messageTypeName(m.body);
  return r.error();
}

TEST(MessageCodec, EveryMessageSurvivesARoundTrip) {
  MessageEncoder encoder;
  for (const Message& m : oneOfEach()) {
    const std::vector<uint8_t> bytes = encodeMessage(m);
    const DecodeResult r = decodeMessage(bytes.data(), bytes.size());
    ASSERT_TRUE(r.ok()) << messageTypeName(m.body) << ": " << r.error();
    EXPECT_EQ(*r.message, m) << messageTypeName(m.body);
    // The reusing encoder writes the same bytes.
    const std::span<const uint8_t> again = encoder.encode(m);
    EXPECT_EQ(std::vector<uint8_t>(again.begin(), again.end()), bytes);
  }
}

TEST(MessageCodec, AlphaRunPartialImagesAreCheckedOnDecoding) {
  std::vector<uint8_t> rgba(40 * 30 * 4, 0), runs;
  for (int i = 100; i < 400; ++i) rgba[4 * i] = uint8_t(i), rgba[4 * i + 3] = 200;
  encodeAlphaRuns(rgba, runs);
  Message m;
  m.sender = "node1";
  m.body = PartialImageData{1, 40, 30, ImageEncoding::kAlphaRuns, runs};
  const std::vector<uint8_t> bytes = encodeMessage(m);
  const DecodeResult ok = decodeMessage(bytes.data(), bytes.size(), {});
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(std::get<PartialImageData>(ok.message->body).data, runs);
  m.body = PartialImageData{1, 40, 31, ImageEncoding::kAlphaRuns, runs};  // too few pixels
  const std::vector<uint8_t> short_bytes = encodeMessage(m);
  const DecodeResult bad = decodeMessage(short_bytes.data(), short_bytes.size(), {});
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("alpha-run data"), std::string::npos) << bad.error();
}

// A node's image of the actor (its colours vary smoothly across him) travels compressed, a
// third of its alpha runs or less, and reads back as exactly those runs; a compressed frame with
// a byte changed is refused as corrupt, not blended.
TEST(MessageCodec, PartialImagesTravelCompressedAndCorruptOnesAreRefused) {
  constexpr int kWidth = 160, kHeight = 120;
  std::vector<uint8_t> rgba(size_t(kWidth) * kHeight * 4, 0), runs;
  std::mt19937 random(3);
  for (int y = 30; y < 100; ++y)
    for (int x = 50 + y % 7; x < 110 - y % 5; ++x) {
      uint8_t* p = &rgba[(size_t(y) * kWidth + x) * 4];
      p[0] = uint8_t(80 + x / 2 + random() % 3), p[1] = uint8_t(60 + y / 3 + random() % 3);
      p[2] = uint8_t(40 + (x + y) / 4), p[3] = uint8_t(200 + random() % 4);
    }
  encodeAlphaRuns(rgba, runs);
  Message m = envelope(PartialImageData{0, kWidth, kHeight, ImageEncoding::kAlphaRuns, runs});
  const std::vector<uint8_t> bytes = encodeMessage(m);
  EXPECT_LT(bytes.size(), runs.size() * 2 / 3);
  const DecodeResult ok = decodeMessage(bytes.data(), bytes.size());
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(*ok.message, m);
  const uint8_t magic[] = {0x28, 0xb5, 0x2f, 0xfd};  // a zstd frame's first bytes
  const auto frame = std::search(bytes.begin(), bytes.end(), std::begin(magic), std::end(magic));
  ASSERT_NE(frame, bytes.end());
  std::vector<uint8_t> corrupt = bytes;
  corrupt[size_t(frame - bytes.begin()) + 40] ^= 0x10;
  const DecodeResult bad = decodeMessage(corrupt.data(), corrupt.size());
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("partial image 160x120: compressed alpha-run data of"),
            std::string::npos)
      << bad.error();
}

TEST(MessageCodec, EmptyTruncatedAndRandomBuffersAreRefused) {
  EXPECT_EQ(decodeMessage(nullptr, 0, {}).error(), "empty message");
  const uint8_t one = 0;
  EXPECT_FALSE(decodeMessage(&one, 1, {}).ok());
  for (const Message& m : oneOfEach()) {
    const std::vector<uint8_t> bytes = encodeMessage(m);
    for (size_t n = 1; n < bytes.size(); n += 1 + n / 16) {
      const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(n));
      const DecodeResult r = decodeMessage(cut.data(), cut.size(), {});
      EXPECT_FALSE(r.ok()) << messageTypeName(m.body) << " cut to " << n << " bytes";
      EXPECT_FALSE(r.error().empty());
    }
  }
  std::mt19937 random(5);
  for (int i = 0; i < 2000; ++i) {
    std::vector<uint8_t> noise(1 + random() % 512);
    for (uint8_t& b : noise) b = static_cast<uint8_t>(random());
    // Half of them look like ours, so that the verifier, not the identifier, has to refuse them.
    if (i % 2 == 0 && noise.size() >= 8) std::memcpy(&noise[4], "LUMI", 4);
    const DecodeResult r = decodeMessage(noise.data(), noise.size(), {});
    EXPECT_TRUE(r.ok() || !r.error().empty());
  }
}

TEST(MessageCodec, FlippedBytesNeverCrash) {
  std::mt19937 random(11);
  for (const Message& m : oneOfEach()) {
    const std::vector<uint8_t> bytes = encodeMessage(m);
    for (int i = 0; i < 300; ++i) {
      std::vector<uint8_t> bent = bytes;
      for (int k = 0; k < 3; ++k) bent[random() % bent.size()] = static_cast<uint8_t>(random());
      const DecodeResult r = decodeMessage(bent.data(), bent.size(), {});
      EXPECT_TRUE(r.ok() || !r.error().empty());
    }
  }
}

TEST(MessageCodec, WrongVersionNamesBoth) {
  Message m = oneOfEach()[0];
  m.version = kProtocolVersion + 1;
  EXPECT_EQ(decodeError(m), "protocol version " + std::to_string(kProtocolVersion + 1) +
                                ", expected " + std::to_string(kProtocolVersion));
}

TEST(MessageCodec, OversizedBuffersAreRefusedBeforeReading) {
  const std::vector<uint8_t> bytes = encodeMessage(oneOfEach()[4]);
  MessageLimits limits;
  limits.max_bytes = bytes.size() - 1;
  const DecodeResult r = decodeMessage(bytes.data(), bytes.size(), limits);
  EXPECT_NE(r.error().find("at most " + std::to_string(bytes.size() - 1)), std::string::npos)
      << r.error();
}

TEST(MessageCodec, CountsOverTheLimitsAreRefused) {
  MessageLimits limits;
  limits.max_cameras = 2;
  HelloData hello{"node1", {"a", "b", "c"}, kProtocolVersion, {}};
  EXPECT_EQ(decodeError(envelope(hello), limits), "hello: 3 cameras, at most 2 allowed");
  HeartbeatData heartbeat;
  heartbeat.cameras.resize(3);
  EXPECT_EQ(decodeError(envelope(heartbeat), limits), "heartbeat: 3 cameras, at most 2 allowed");
  SilhouettesData silhouettes;
  silhouettes.masks.push_back({7, 8, 1, {0}, {}});
  EXPECT_EQ(decodeError(envelope(silhouettes), limits),
            "silhouettes: mask 0 (camera 7): camera index out of range, the rig has 2");

  limits.max_vertices = 1000;
  OffsetsData offsets{21, std::vector<uint8_t>(1001, 0), {}};
  EXPECT_EQ(decodeError(envelope(offsets), limits), "offsets: 1001 vertices, at most 1000 allowed");
  VertexStatisticsData stats;
  stats.vertex_count = 1001;
  stats.offset_count = 21;
  EXPECT_EQ(decodeError(envelope(stats), limits),
            "vertex statistics: 1001 vertices, at most 1000 allowed");

  PoseData pose;
  pose.angles.resize(3 * 200);
  EXPECT_EQ(decodeError(envelope(pose)), "pose: 200 joints, at most 128 allowed");

  limits = {};
  limits.max_string_bytes = 8;
  HelloData long_name{"a-very-long-node-name", {}, kProtocolVersion, {}};
  EXPECT_EQ(decodeError(envelope(long_name), limits),
            "hello: node name: 21 bytes, at most 8 allowed");
}

TEST(MessageCodec, InconsistentSizesSayWhatWasExpected) {
  VertexStatisticsData stats;
  stats.vertex_count = 41000;
  stats.offset_count = 21;
  stats.packed.assign(12, 1);
  EXPECT_EQ(decodeError(envelope(stats)),
            "vertex statistics: 41000 vertices x 21 offsets needs 866133 to 10439633 packed bytes, "
            "got 12");
  stats.vertex_count = 2;
  stats.offset_count = 3;
  stats.packed.assign(157, 0);  // 0 where the packed form has its sums' width: compressed
  EXPECT_EQ(decodeError(envelope(stats)),
            "vertex statistics: 2 vertices x 3 offsets needs 12 to 156 compressed bytes, got 157");

  stats = std::get<VertexStatisticsData>(oneOfEach()[4].body);
  stats.packed[0] = 4;
  EXPECT_EQ(decodeError(envelope(stats)),
            "vertex statistics: the header says 4 vertices x 3 offsets");

  SilhouettesData silhouettes;
  silhouettes.masks.push_back({0, 13, 7, std::vector<uint8_t>(11, 0), {}});
  EXPECT_EQ(decodeError(envelope(silhouettes)),
            "silhouettes: mask 0 (camera 0): 13x7 needs 12 mask bytes, got 11");
  // Colours for each cell of the actor, counted without the last byte's padding bits.
  silhouettes.masks[0].bits.assign(12, 0);
  silhouettes.masks[0].bits[0] = 0x03;
  silhouettes.masks[0].bits[11] = 0xf8;  // cells 88-90 are 0; bits 3-7 are no cells
  silhouettes.masks[0].colours.assign(9, 7);
  EXPECT_EQ(decodeError(envelope(silhouettes)),
            "silhouettes: mask 0 (camera 0): 2 cells of the actor need 6 colour bytes, got 9");
  silhouettes.masks[0].colours.resize(6);
  const std::vector<uint8_t> coloured = encodeMessage(envelope(silhouettes));
  EXPECT_TRUE(decodeMessage(coloured.data(), coloured.size()).ok());

  // A mask sent as runs (smaller than its bits) reads back bit for bit; runs that are cut short,
  // run past the mask or stop short of it are refused, saying where.
  SilhouettesData runs;
  runs.masks.push_back({3, 20, 10, std::vector<uint8_t>(25, 0), {}});
  for (int i = 77; i < 80; ++i) runs.masks[0].bits[size_t(i / 8)] |= uint8_t(1u << (i % 8));
  const std::vector<uint8_t> sent = encodeMessage(envelope(runs));
  const DecodeResult read = decodeMessage(sent.data(), sent.size());
  ASSERT_TRUE(read.ok()) << read.error();
  EXPECT_EQ(std::get<SilhouettesData>(read.message->body), runs);
  // Off 77, on 3, off 120: three bytes on the wire where the bits take 25.
  const uint8_t wire[] = {77, 3, 120};
  const auto at = std::search(sent.begin(), sent.end(), std::begin(wire), std::end(wire));
  ASSERT_NE(at, sent.end());
  const auto refused = [&](uint8_t last) {
    std::vector<uint8_t> bytes = sent;
    bytes[size_t(at - sent.begin()) + 2] = last;
    const DecodeResult r = decodeMessage(bytes.data(), bytes.size());
    return r.ok() ? std::string("accepted") : r.error();
  };
  EXPECT_EQ(refused(121),
            "silhouettes: mask 0 (camera 3): runs: the run at byte 2 reaches "
            "pixel 201, the mask has 200");
  EXPECT_EQ(refused(119),
            "silhouettes: mask 0 (camera 3): runs cover 199 of the mask's 200 pixels");
  EXPECT_EQ(refused(0x80 | 120),
            "silhouettes: mask 0 (camera 3): runs: the length at byte 2 is cut short");

  PoseData pose;
  pose.angles.resize(7);  // the encoder writes 2 joints
  EXPECT_EQ(decodeError(envelope(pose)), "pose: 2 joints need 6 angles, got 7");
  pose.angles.resize(6);
  pose.scale = 5.0f;  // no actor is five times the generic human
  EXPECT_EQ(decodeError(envelope(pose)), "pose: scale 5.000000 outside 0.5..2");

  OffsetsData offsets{21, {3, 21}, {}};
  EXPECT_EQ(decodeError(envelope(offsets)), "offsets: vertex 1 has offset 21, expected below 21");
  OffsetsData masks{21, {3, 4}, {1, 2, 3}};
  EXPECT_EQ(decodeError(envelope(masks)),
            "offsets: 3 visibility masks for 2 vertices, expected none or one a vertex");

  PartialImageData raw{0, 4, 4, ImageEncoding::kRawRgba, std::vector<uint8_t>(63)};
  EXPECT_EQ(decodeError(envelope(raw)), "partial image 4x4: raw RGBA needs 64 bytes, got 63");
  PartialImageData rle{0, 4, 4, ImageEncoding::kRleRgba, {2, 0, 0, 0, 0}};
  EXPECT_EQ(decodeError(envelope(rle)), "partial image 4x4: RLE runs cover 3 pixels, expected 16");
  PartialImageData odd{0, 4, 4, static_cast<ImageEncoding>(9), {}};
  EXPECT_EQ(decodeError(envelope(odd)), "partial image 4x4: unknown encoding 9");

  HelloData nameless{"", {}, kProtocolVersion, {}};
  EXPECT_EQ(decodeError(envelope(nameless)), "hello: the node name is empty");
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

TEST(MessageCodec, TakeNamesThatAreNotAPlainFolderNameAreRefused) {
  // A take names a folder on every node's disk: nothing that climbs out of the takes folder,
  // hides, or needs quoting gets through the decoder.
  for (const std::string& take :
       std::vector<std::string>{"../etc", "a/b", ".hidden", "take one", std::string(65, 'a'),
                                std::string("nul\0byte", 8)}) {
    EXPECT_NE(decodeError(envelope(RecordData{take, 0, 10})).find("record: take name"),
              std::string::npos)
        << take;
    HeartbeatData heartbeat;
    heartbeat.take.take = take;
    EXPECT_NE(decodeError(envelope(heartbeat)).find("heartbeat: take: take name"),
              std::string::npos)
        << take;
  }
  EXPECT_EQ(decodeError(envelope(RecordData{"a/b", 0, 10})),
            "record: take name 'a/b' has a character other than letters, digits, '-', '_' and '.'");
  EXPECT_EQ(decodeError(envelope(RecordData{"a\nb", 0, 10})),
            "record: take name 'a?b' has a character other than letters, digits, '-', '_' and "
            "'.'");  // nothing unprintable reaches a log
  EXPECT_EQ(decodeError(envelope(RecordData{std::string(2000, 'a'), 0, 10})),
            "record: take name: 2000 bytes, at most 1024 allowed");
  EXPECT_EQ(decodeError(envelope(RecordData{"t", 10, 9})),
            "record: frames 10 to 9, expected 0 <= first <= last");
  EXPECT_EQ(decodeError(envelope(RecordData{"t", -1, 9})),
            "record: frames -1 to 9, expected 0 <= first <= last");
  EXPECT_EQ(checkTakeName("Take_2026-12-01.a").error(), "");
  // An empty take is "none": the stop of every take.
  const std::vector<uint8_t> bytes = encodeMessage(envelope(RecordData{}));
  EXPECT_TRUE(decodeMessage(bytes.data(), bytes.size()).ok());
  // A shift of the frame ids beyond half their range (a hostile studio) would wrap them.
  EXPECT_EQ(decodeError(envelope(FrameIdsData{std::numeric_limits<int64_t>::min()})),
            "frame ids: offset -9223372036854775808 beyond half the ids' range");
}

TEST(MessageCodec, MalformedViewsAreRefusedWithTheirReason) {
  Message message;
  message.sender = "studio";
  message.body = ViewData{0, 320, 240, 300, 300, 160, 120, {1, 0, 0, 0, 1, 0, 0, 0}, {0, 0, 3}, {}};
  std::vector<uint8_t> bytes = encodeMessage(message);
  DecodeResult result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(result.error(),
            "view: expected a rotation of 9 numbers and a translation of 3, got 8 and 3");
  message.body =
      ViewData{0, 320, 240, -300, 300, 160, 120, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 3}, {}};
  bytes = encodeMessage(message);
  result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_EQ(result.error(), "view: expected finite numbers and positive focal lengths");
  ViewData view{0, 320, 240, 300, 300, 160, 120, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 3}, {}};
  view.clones = {1, 0};  // a clone is 3 numbers
  message.body = view;
  bytes = encodeMessage(message);
  result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_EQ(
      result.error(),
      "view: clones take 3 numbers each (offset x, y, yaw), at most 64 clones; got 2 numbers");
  view.clones.assign(65 * 3, 0.0f);
  message.body = view;
  bytes = encodeMessage(message);
  result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_EQ(result.error(),
            "view: clones take 3 numbers each (offset x, y, yaw), at most 64 clones; "
            "got 195 numbers");
  view.clones = {1, std::numeric_limits<float>::quiet_NaN(), 0};
  message.body = view;
  bytes = encodeMessage(message);
  result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_EQ(result.error(), "view: a clone's offset or turn is not a finite number within 1000");
  // Few pixels, but wider than a framebuffer can be (the node's renderer would throw).
  view.clones.clear();
  view.width = 20000, view.height = 10;
  message.body = view;
  bytes = encodeMessage(message);
  result = decodeMessage(bytes.data(), bytes.size());
  EXPECT_EQ(result.error(), "view: 20000x10 pixels, expected at most 8192 a side");
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

// Camera names in heartbeats reach the studio's log, `lumistage run`'s report and its JSON: a
// node (a plain-mode peer with a valid node name will do) that sends a line break or terminal
// escapes in one is refused, as a node name is.
TEST(MessageCodec, NamesThatAreNoCameraOrNodeNamesAreRefused) {
  HeartbeatData forged;
  forged.cameras = {{"cam1", 10, 0, 30.f, ""}, {"cam2\n[info] forged", 10, 0, 30.f, ""}};
  EXPECT_EQ(decodeError(envelope(forged)),
            "heartbeat: camera 1: its name is not a valid camera name");
  HeartbeatData escape;
  escape.cameras = {{"\x1b[2Jcam1", 10, 0, 30.f, ""}};
  EXPECT_EQ(decodeError(envelope(escape)),
            "heartbeat: camera 0: its name is not a valid camera name");
  HelloData hello{"node1", {"cam1", "cam 2"}, kProtocolVersion, {}};
  EXPECT_EQ(decodeError(envelope(hello)), "hello: camera 1: its name is not a valid camera name");
  HelloData node{"node1\x1b", {}, kProtocolVersion, {}};
  EXPECT_EQ(decodeError(envelope(node)), "hello: the node name is not a valid node name");
  // Free text (a last error) still decodes: the studio shows it escaped (StudioCoordinator).
  HeartbeatData free_text;
  free_text.cameras = {{"cam1", 10, 0, 30.f, "bad\x1b[2J"}};
  const std::vector<uint8_t> text = encodeMessage(envelope(free_text));
  EXPECT_TRUE(decodeMessage(text.data(), text.size()).ok());
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

// The studio's message limit follows from largestNodeMessage (issue 54: at 64 MB every connection
// could make it buffer that much). It must hold what a node legitimately sends at those sizes,
// in its worst case: a partial image of noise (no two equal pixels, no empty one between), every
// silhouette mask of the largest camera, a heartbeat of every string at its longest.
TEST(MessageCodec, TheLargestNodeMessageHoldsWhatANodeSendsAtItsWorst) {
  NodeMessageSizes sizes;
  sizes.cameras = 4;
  sizes.camera_pixels = 640 * 480;
  sizes.silhouette_step = 4;
  sizes.statistics_samples = 500 * 18;
  sizes.view_pixels = 200 * 150;
  const MessageLimits limits;
  const size_t largest = largestNodeMessage(sizes, limits);
  const auto wire = [](MessageBody body) {
    return encodeMessage(envelope(std::move(body))).size();
  };

  // Noise that neither runs nor the literals' differences compress; no pixel empty (alpha odd).
  std::vector<uint8_t> noise(size_t(sizes.view_pixels) * 4);
  std::mt19937 random(7);
  for (size_t i = 0; i < noise.size(); ++i) noise[i] = uint8_t(random() | (i % 4 == 3));
  std::vector<uint8_t> runs;
  encodeAlphaRuns(noise, runs);
  // Every other pixel empty: a pair of run lengths for each literal pixel.
  std::vector<uint8_t> sparse = noise;
  for (size_t p = 0; p < sparse.size() / 4; p += 2) std::fill_n(sparse.begin() + p * 4, 4, 0);
  std::vector<uint8_t> sparse_runs;
  encodeAlphaRuns(sparse, sparse_runs);
  for (const auto& [encoding, data] : {std::pair{ImageEncoding::kRawRgba, noise},
                                       std::pair{ImageEncoding::kRleRgba, encodeRleRgba(noise)},
                                       std::pair{ImageEncoding::kAlphaRuns, runs},
                                       std::pair{ImageEncoding::kAlphaRuns, sparse_runs}}) {
    const size_t bytes = wire(PartialImageData{0, 200, 150, encoding, data});
    EXPECT_LE(bytes, largest) << int(encoding);
    // The literal pixels are in it (half of them in the sparse image).
    EXPECT_GT(bytes, size_t(sizes.view_pixels) * (data == sparse_runs ? 2 : 3)) << int(encoding);
  }

  SilhouettesData masks;
  for (int c = 0; c < sizes.cameras; ++c)
    masks.masks.push_back({c, 160, 120, std::vector<uint8_t>(160 * 120 / 8, 0xff),
                           std::vector<uint8_t>(160 * 120 * 3, 0xa5)});
  EXPECT_LE(wire(masks), largest);

  HeartbeatData heartbeat;
  const std::string longest(limits.max_string_bytes, 'e');
  for (int c = 0; c < sizes.cameras; ++c)
    heartbeat.cameras.push_back({"cam0" + std::to_string(c), 1, 1, 30.f, longest});
  heartbeat.take = {"take-1", 1, 2, 3, 4, 5, false, longest, 1, longest};
  EXPECT_LE(wire(heartbeat), largest);

  // And no more than a margin above the largest of them: the limit is the rig's, not 64 MB.
  EXPECT_LT(largest, std::max(wire(masks),
                              wire(PartialImageData{0, 200, 150, ImageEncoding::kRawRgba, noise})) *
                             5 / 4 +
                         4096);
}

}  // namespace
}  // namespace lumistage
