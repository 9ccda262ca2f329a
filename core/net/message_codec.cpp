#include "core/net/message_codec.h"

#include <flatbuffers/flatbuffers.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "core/base/names.h"
#include "core/imaging/cell_colours.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/compact_forms.h"
#include "core/refine/refinement_statistics.h"
#include "messages_generated.h"

namespace lumistage {

namespace fb = net::fb;

namespace {

// ---------------------------------------------------------------------------------------------
// Encoding

flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<flatbuffers::String>>> stringVector(
    flatbuffers::FlatBufferBuilder& b, const std::vector<std::string>& strings) {
  std::vector<flatbuffers::Offset<flatbuffers::String>> offsets;
  offsets.reserve(strings.size());
  for (const std::string& s : strings) offsets.push_back(b.CreateString(s));
  return b.CreateVector(offsets);
}

struct BodyEncoder {
  flatbuffers::FlatBufferBuilder& b;

  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const HelloData& m) const {
    const auto name = b.CreateString(m.node_name);
    const auto cameras = stringVector(b, m.camera_names);
    const auto capabilities = stringVector(b, m.capabilities);
    return {fb::Body::Hello,
            fb::CreateHello(b, name, cameras, m.protocol_version, capabilities).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const HeartbeatData& m) const {
    std::vector<flatbuffers::Offset<fb::CameraHealth>> cameras;
    for (const CameraHealthData& c : m.cameras) {
      const auto name = b.CreateString(c.camera);
      const auto error = b.CreateString(c.last_error);
      const auto key = b.CreateString(c.key);
      cameras.push_back(
          fb::CreateCameraHealth(b, name, c.frames, c.dropped, c.frame_rate, error, key));
    }
    const auto vector = b.CreateVector(cameras);
    const TakeStatusData& t = m.take;
    const auto take_name = b.CreateString(t.take);
    const auto take_error = b.CreateString(t.error);
    const auto disk = b.CreateString(t.disk);
    const auto take =
        fb::CreateTakeStatus(b, take_name, t.first_frame, t.last_frame, t.written, t.dropped,
                             t.bytes, t.finished, take_error, t.free_bytes, disk);
    return {fb::Body::Heartbeat, fb::CreateHeartbeat(b, vector, m.bytes_sent, m.cpu, take).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const FrameIdsData& m) const {
    return {fb::Body::FrameIds, fb::CreateFrameIds(b, m.offset).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const RecordData& m) const {
    const auto take = b.CreateString(m.take);
    return {fb::Body::Record, fb::CreateRecord(b, take, m.first_frame, m.last_frame).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const SilhouettesData& m) const {
    std::vector<flatbuffers::Offset<fb::SilhouetteMask>> masks;
    thread_local std::vector<uint8_t> runs;  // reused: no allocation a message once grown
    for (const SilhouetteMaskData& s : m.masks) {
      const size_t cells = size_t(s.width) * size_t(s.height);
      // Bits of another size than the mask's are sent as they are, for the reader to refuse.
      const bool sized = s.bits.size() == (cells + 7) / 8;
      if (sized) encodeMaskRuns(s.bits, cells, runs);
      const bool as_runs = sized && runs.size() < s.bits.size();
      const auto bits = as_runs ? 0 : b.CreateVector(s.bits);
      const auto run_bytes = as_runs ? b.CreateVector(runs) : 0;
      const auto colours = s.colours.empty() ? 0 : b.CreateVector(s.colours);
      masks.push_back(fb::CreateSilhouetteMask(
          b, static_cast<uint16_t>(s.camera), static_cast<uint16_t>(s.width),
          static_cast<uint16_t>(s.height), bits, colours, run_bytes));
    }
    const auto vector = b.CreateVector(masks);
    return {fb::Body::Silhouettes, fb::CreateSilhouettes(b, vector).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const PoseData& m) const {
    const auto angles = b.CreateVector(m.angles);
    const auto joints = static_cast<uint16_t>(m.angles.size() / 3);
    return {fb::Body::Pose,
            fb::CreatePose(b, m.root[0], m.root[1], m.root[2], joints, angles, m.scale).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const VertexStatisticsData& m) const {
    const auto packed = b.CreateVector(m.packed);
    return {
        fb::Body::VertexStatistics,
        fb::CreateVertexStatistics(b, m.vertex_count, static_cast<uint8_t>(m.offset_count), packed)
            .Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const OffsetsData& m) const {
    const auto offsets = b.CreateVector(m.offsets);
    const auto visibility = m.visibility.empty() ? 0 : b.CreateVector(m.visibility);
    return {
        fb::Body::Offsets,
        fb::CreateOffsets(b, static_cast<uint8_t>(m.offset_count), offsets, visibility).Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const PartialImageData& m) const {
    // Alpha runs go compressed where that is smaller (the scratch reused: no allocation once
    // grown).
    thread_local std::vector<uint8_t> differences, compressed;
    const bool zstd =
        m.encoding == ImageEncoding::kAlphaRuns &&
        compressAlphaRuns(m.data, size_t(m.width) * size_t(m.height), differences, compressed);
    const auto data = b.CreateVector(zstd ? compressed : m.data);
    const auto encoding =
        zstd ? fb::ImageEncoding::alpha_runs_zstd : static_cast<fb::ImageEncoding>(m.encoding);
    return {fb::Body::PartialImage,
            fb::CreatePartialImage(b, static_cast<uint16_t>(m.view), static_cast<uint16_t>(m.width),
                                   static_cast<uint16_t>(m.height), encoding, data)
                .Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const ViewData& m) const {
    const auto rotation = b.CreateVector(m.rotation);
    const auto translation = b.CreateVector(m.translation);
    const auto clones = b.CreateVector(m.clones);
    return {fb::Body::View,
            fb::CreateView(b, static_cast<uint16_t>(m.view), static_cast<uint16_t>(m.width),
                           static_cast<uint16_t>(m.height), m.fx, m.fy, m.cx, m.cy, rotation,
                           translation, clones)
                .Union()};
  }
  std::pair<fb::Body, flatbuffers::Offset<void>> operator()(const FrameTimestampsData& m) const {
    std::vector<flatbuffers::Offset<fb::StageTime>> stages;
    for (const StageTimeData& s : m.stages) {
      const auto name = b.CreateString(s.stage);
      stages.push_back(fb::CreateStageTime(b, name, s.ns));
    }
    const auto vector = b.CreateVector(stages);
    return {fb::Body::FrameTimestamps, fb::CreateFrameTimestamps(b, vector).Union()};
  }
};

void encodeInto(flatbuffers::FlatBufferBuilder& b, const Message& message) {
  b.Clear();
  const auto [type, body] = std::visit(BodyEncoder{b}, message.body);
  const auto sender = b.CreateString(message.sender);
  const auto envelope =
      fb::CreateEnvelope(b, message.version, sender, message.frame_id, message.sent_ns, type, body);
  fb::FinishEnvelopeBuffer(b, envelope);
}

// ---------------------------------------------------------------------------------------------
// Decoding. Every check names the message, the field, the expected and the actual value, since
// the reason goes to a log next to the sender's name and is all anyone will have to go on.

std::string num(uint64_t v) {
  return std::to_string(v);
}

Status checkString(const flatbuffers::String* s, const char* what, const MessageLimits& limits) {
  if (s != nullptr && s->size() > limits.max_string_bytes) {
    return Status::failure(std::string(what) + ": " + num(s->size()) + " bytes, at most " +
                           num(limits.max_string_bytes) + " allowed");
  }
  return {};
}

std::string copyString(const flatbuffers::String* s) {
  return s == nullptr ? std::string() : std::string(s->c_str(), s->size());
}

template <typename T>
std::vector<T> copyVector(const flatbuffers::Vector<T>* v) {
  if (v == nullptr) return {};
  std::vector<T> out(v->size());
  // Scalars are little-endian on the wire, as on every machine we build for.
  static_assert(flatbuffers::is_same<T, uint8_t>::value ||
                flatbuffers::is_same<T, uint16_t>::value ||
                flatbuffers::is_same<T, uint32_t>::value || flatbuffers::is_same<T, float>::value);
  if (!out.empty()) std::memcpy(out.data(), v->Data(), out.size() * sizeof(T));
  return out;
}

template <typename T>
size_t sizeOf(const flatbuffers::Vector<T>* v) {
  return v == nullptr ? 0 : v->size();
}

Status decodeHello(const fb::Hello& in, const MessageLimits& limits, HelloData& out) {
  if (Status c = checkString(in.node_name(), "hello: node name", limits); !c.ok()) return c;
  const size_t cameras = sizeOf(in.camera_names());
  if (cameras > static_cast<size_t>(limits.max_cameras)) {
    return Status::failure("hello: " + num(cameras) + " cameras, at most " +
                           num(limits.max_cameras) + " allowed");
  }
  const size_t capabilities = sizeOf(in.capabilities());
  if (capabilities > 64)
    return Status::failure("hello: " + num(capabilities) + " capabilities, at most 64");
  out.node_name = copyString(in.node_name());
  if (out.node_name.empty()) return Status::failure("hello: the node name is empty");
  if (!isValidName(out.node_name))
    return Status::failure("hello: the node name is not a valid node name");
  out.protocol_version = in.protocol_version();
  for (size_t i = 0; i < cameras; ++i) {
    const flatbuffers::String* name =
        in.camera_names()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (Status c = checkString(name, "hello: camera name", limits); !c.ok()) return c;
    out.camera_names.push_back(copyString(name));
    if (!isValidName(out.camera_names.back())) {
      return Status::failure("hello: camera " + num(i) + ": its name is not a valid camera name");
    }
  }
  for (size_t i = 0; i < capabilities; ++i) {
    const flatbuffers::String* name =
        in.capabilities()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (Status c = checkString(name, "hello: capability", limits); !c.ok()) return c;
    out.capabilities.push_back(copyString(name));
  }
  return {};
}

Status decodeHeartbeat(const fb::Heartbeat& in, const MessageLimits& limits, HeartbeatData& out) {
  const size_t cameras = sizeOf(in.cameras());
  if (cameras > static_cast<size_t>(limits.max_cameras)) {
    return Status::failure("heartbeat: " + num(cameras) + " cameras, at most " +
                           num(limits.max_cameras) + " allowed");
  }
  out.bytes_sent = in.bytes_sent();
  out.cpu = in.cpu();
  for (size_t i = 0; i < cameras; ++i) {
    const fb::CameraHealth* c = in.cameras()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (c == nullptr) return Status::failure("heartbeat: camera " + num(i) + " is missing");
    if (Status e = checkString(c->camera(), "heartbeat: camera name", limits); !e.ok()) return e;
    // Names reach the studio's log and reports: one that is no camera name (a line break, terminal
    // escapes) is refused here, as a node name is at the endpoint.
    if (!isValidName(copyString(c->camera()))) {
      return Status::failure("heartbeat: camera " + num(i) +
                             ": its name is not a valid camera name");
    }
    if (Status e = checkString(c->last_error(), "heartbeat: last error", limits); !e.ok()) {
      return e;
    }
    if (Status e = checkString(c->key(), "heartbeat: key", limits); !e.ok()) return e;
    out.cameras.push_back({copyString(c->camera()), c->frames(), c->dropped(), c->frame_rate(),
                           copyString(c->last_error()), copyString(c->key())});
  }
  if (const fb::TakeStatus* t = in.take()) {
    if (Status e = checkString(t->take(), "heartbeat: take name", limits); !e.ok()) return e;
    const std::string take = copyString(t->take());
    if (!take.empty()) {
      if (Status named = checkTakeName(take); !named.ok())
        return Status::failure("heartbeat: take: " + named.error());
    }
    if (Status e = checkString(t->error(), "heartbeat: take error", limits); !e.ok()) return e;
    if (Status e = checkString(t->disk(), "heartbeat: take disk", limits); !e.ok()) return e;
    out.take = {take,
                t->first_frame(),
                t->last_frame(),
                t->written(),
                t->dropped(),
                t->bytes(),
                t->finished(),
                copyString(t->error()),
                std::max<int64_t>(-1, t->free_bytes()),
                copyString(t->disk())};
  }
  return {};
}

Status decodeSilhouettes(const fb::Silhouettes& in, const MessageLimits& limits,
                         SilhouettesData& out) {
  const size_t masks = sizeOf(in.masks());
  if (masks > static_cast<size_t>(limits.max_cameras)) {
    return Status::failure("silhouettes: " + num(masks) + " masks, at most " +
                           num(limits.max_cameras) + " allowed");
  }
  for (size_t i = 0; i < masks; ++i) {
    const fb::SilhouetteMask* m = in.masks()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (m == nullptr) return Status::failure("silhouettes: mask " + num(i) + " is missing");
    const std::string where = "silhouettes: mask " + num(i) + " (camera " + num(m->camera()) + ")";
    if (m->camera() >= limits.max_cameras) {
      return Status::failure(where + ": camera index out of range, the rig has " +
                             num(limits.max_cameras));
    }
    const uint64_t pixels = uint64_t{m->width()} * m->height();
    if (pixels > static_cast<uint64_t>(limits.max_mask_pixels)) {
      return Status::failure(where + ": " + num(m->width()) + "x" + num(m->height()) +
                             " pixels, at most " + num(limits.max_mask_pixels) + " allowed");
    }
    std::vector<uint8_t> bits;
    if (sizeOf(m->runs()) > 0) {
      if (sizeOf(m->bits()) > 0)
        return Status::failure(where + ": both bits and runs, one of them expected");
      std::string why;
      if (!decodeMaskRuns({m->runs()->data(), m->runs()->size()}, size_t(pixels), bits, why))
        return Status::failure(where + ": " + why);
    } else {
      const uint64_t expected = (pixels + 7) / 8;
      if (sizeOf(m->bits()) != expected) {
        return Status::failure(where + ": " + num(m->width()) + "x" + num(m->height()) + " needs " +
                               num(expected) + " mask bytes, got " + num(sizeOf(m->bits())));
      }
      bits = copyVector(m->bits());
    }
    // Colours, where sent: three bytes a cell of the actor.
    const size_t set = countActorCells(bits.data(), bits.size(), size_t(pixels));
    const size_t colours = sizeOf(m->colours());
    if (colours != 0 && colours != 3 * set) {
      return Status::failure(where + ": " + num(set) + " cells of the actor need " + num(3 * set) +
                             " colour bytes, got " + num(colours));
    }
    out.masks.push_back(
        {m->camera(), m->width(), m->height(), std::move(bits), copyVector(m->colours())});
  }
  return {};
}

Status decodePose(const fb::Pose& in, const MessageLimits& limits, PoseData& out) {
  if (in.joint_count() > limits.max_joints) {
    return Status::failure("pose: " + num(in.joint_count()) + " joints, at most " +
                           num(limits.max_joints) + " allowed");
  }
  const size_t expected = size_t{in.joint_count()} * 3;
  if (sizeOf(in.angles()) != expected) {
    return Status::failure("pose: " + num(in.joint_count()) + " joints need " + num(expected) +
                           " angles, got " + num(sizeOf(in.angles())));
  }
  if (!(in.scale() >= 0.5f && in.scale() <= 2.0f)) {
    return Status::failure("pose: scale " + std::to_string(in.scale()) + " outside 0.5..2");
  }
  out.root[0] = in.root_x();
  out.root[1] = in.root_y();
  out.root[2] = in.root_z();
  out.angles = copyVector(in.angles());
  out.scale = in.scale();
  return {};
}

Status decodeVertexStatistics(const fb::VertexStatistics& in, const MessageLimits& limits,
                              VertexStatisticsData& out) {
  const uint64_t vertices = in.vertex_count(), offsets = in.offset_count();
  if (vertices > limits.max_vertices) {
    return Status::failure("vertex statistics: " + num(vertices) + " vertices, at most " +
                           num(limits.max_vertices) + " allowed");
  }
  if (offsets == 0 || offsets > static_cast<uint64_t>(limits.max_offsets)) {
    return Status::failure("vertex statistics: " + num(offsets) + " offsets, expected 1 to " +
                           num(limits.max_offsets));
  }
  // The statistics' wire form (core/refine/refinement_statistics.h), packed or compressed: a
  // header that starts with the vertex and offset counts, then at most 12 bytes a sample and a
  // contour bit a point packed, zstd's bound of that compressed. Its contents are checked where it
  // is combined (addEncodedRefinementStatistics).
  const uint64_t samples = vertices * offsets, size = sizeOf(in.packed());
  const bool compressed = size >= kPackedStatisticsHeaderBytes && in.packed()->Get(6) == 0;
  const uint64_t least = compressed
                             ? kCompressedStatisticsHeaderBytes
                             : kPackedStatisticsHeaderBytes + samples + contourBytes(vertices),
                 most = compressed ? maxCompressedStatisticsBytes(samples)
                                   : maxPackedStatisticsBytes(samples);
  if (size < least || size > most) {
    return Status::failure("vertex statistics: " + num(vertices) + " vertices x " + num(offsets) +
                           " offsets needs " + num(least) + " to " + num(most) +
                           (compressed ? " compressed" : " packed") + " bytes, got " + num(size));
  }
  const auto* p = in.packed()->data();
  const uint32_t packed_vertices =
      uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  if (packed_vertices != vertices || p[4] != offsets) {
    return Status::failure("vertex statistics: the header says " + num(packed_vertices) +
                           " vertices x " + num(p[4]) + " offsets");
  }
  out.vertex_count = in.vertex_count();
  out.offset_count = in.offset_count();
  out.packed = copyVector(in.packed());
  return {};
}

Status decodeView(const fb::View& in, const MessageLimits& limits, ViewData& out) {
  if (sizeOf(in.rotation()) != 9 || sizeOf(in.translation()) != 3) {
    return Status::failure("view: expected a rotation of 9 numbers and a translation of 3, got " +
                           num(sizeOf(in.rotation())) + " and " + num(sizeOf(in.translation())));
  }
  const size_t pixels = size_t(in.width()) * in.height();
  if (pixels == 0 || pixels > size_t(limits.max_image_pixels)) {
    return Status::failure("view: " + num(in.width()) + "x" + num(in.height()) +
                           " pixels, expected 1 to " + num(limits.max_image_pixels));
  }
  if (std::max(in.width(), in.height()) > uint32_t(limits.max_view_side)) {
    return Status::failure("view: " + num(in.width()) + "x" + num(in.height()) +
                           " pixels, expected at most " + num(limits.max_view_side) + " a side");
  }
  const size_t clone_numbers = sizeOf(in.clones());
  if (clone_numbers % 3 != 0 || clone_numbers / 3 > size_t(limits.max_clones)) {
    return Status::failure("view: clones take 3 numbers each (offset x, y, yaw), at most " +
                           num(limits.max_clones) + " clones; got " + num(clone_numbers) +
                           " numbers");
  }
  out.rotation = copyVector(in.rotation());
  out.translation = copyVector(in.translation());
  out.clones = copyVector(in.clones());
  for (float v : out.clones) {
    if (!std::isfinite(v) || std::abs(v) > 1000.0f)
      return Status::failure("view: a clone's offset or turn is not a finite number within 1000");
  }
  bool finite = std::isfinite(in.fx()) && std::isfinite(in.fy()) && std::isfinite(in.cx()) &&
                std::isfinite(in.cy());
  for (float v : out.rotation) finite = finite && std::isfinite(v);
  for (float v : out.translation) finite = finite && std::isfinite(v);
  if (!finite || !(in.fx() > 0) || !(in.fy() > 0))
    return Status::failure("view: expected finite numbers and positive focal lengths");
  out.view = in.view();
  out.width = in.width();
  out.height = in.height();
  out.fx = in.fx(), out.fy = in.fy(), out.cx = in.cx(), out.cy = in.cy();
  return {};
}

Status decodeRecord(const fb::Record& in, const MessageLimits& limits, RecordData& out) {
  if (Status e = checkString(in.take(), "record: take name", limits); !e.ok()) return e;
  out.take = copyString(in.take());
  if (!out.take.empty()) {
    if (Status named = checkTakeName(out.take); !named.ok())
      return Status::failure("record: " + named.error());
  }
  out.first_frame = in.first_frame();
  out.last_frame = in.last_frame();
  if (out.first_frame < 0 || out.last_frame < out.first_frame) {
    return Status::failure("record: frames " + std::to_string(out.first_frame) + " to " +
                           std::to_string(out.last_frame) + ", expected 0 <= first <= last");
  }
  return {};
}

Status decodeFrameIds(const fb::FrameIds& in, const MessageLimits&, FrameIdsData& out) {
  // Frame ids count from 0 to half the range (StudioCoordinator): a shift beyond it is no shift
  // between cameras of one rig.
  constexpr int64_t kLimit = std::numeric_limits<int64_t>::max() / 2;
  if (in.offset() < -kLimit || in.offset() > kLimit)
    return Status::failure("frame ids: offset " + std::to_string(in.offset()) +
                           " beyond half the ids' range");
  out.offset = in.offset();
  return {};
}

Status decodeOffsets(const fb::Offsets& in, const MessageLimits& limits, OffsetsData& out) {
  const size_t vertices = sizeOf(in.offsets());
  if (vertices > limits.max_vertices) {
    return Status::failure("offsets: " + num(vertices) + " vertices, at most " +
                           num(limits.max_vertices) + " allowed");
  }
  if (in.offset_count() == 0 || in.offset_count() > limits.max_offsets) {
    return Status::failure("offsets: " + num(in.offset_count()) + " offsets, expected 1 to " +
                           num(limits.max_offsets));
  }
  for (size_t v = 0; v < vertices; ++v) {
    const uint8_t t = in.offsets()->Get(static_cast<flatbuffers::uoffset_t>(v));
    if (t >= in.offset_count()) {
      return Status::failure("offsets: vertex " + num(v) + " has offset " + num(t) +
                             ", expected below " + num(in.offset_count()));
    }
  }
  const size_t masks = sizeOf(in.visibility());
  if (masks != 0 && masks != vertices) {
    return Status::failure("offsets: " + num(masks) + " visibility masks for " + num(vertices) +
                           " vertices, expected none or one a vertex");
  }
  out.offset_count = in.offset_count();
  out.offsets = copyVector(in.offsets());
  out.visibility = copyVector(in.visibility());
  return {};
}

Status decodePartialImage(const fb::PartialImage& in, const MessageLimits& limits,
                          PartialImageData& out) {
  const uint64_t pixels = uint64_t{in.width()} * in.height();
  const std::string where = "partial image " + num(in.width()) + "x" + num(in.height());
  if (pixels > static_cast<uint64_t>(limits.max_image_pixels)) {
    return Status::failure(where + ": at most " + num(limits.max_image_pixels) + " pixels allowed");
  }
  const size_t bytes = sizeOf(in.data());
  switch (in.encoding()) {
    case fb::ImageEncoding::raw_rgba:
      if (bytes != pixels * 4) {
        return Status::failure(where + ": raw RGBA needs " + num(pixels * 4) + " bytes, got " +
                               num(bytes));
      }
      break;
    case fb::ImageEncoding::rle_rgba: {
      if (bytes % 5 != 0) {
        return Status::failure(where + ": RLE data of " + num(bytes) +
                               " bytes is not whole 5-byte runs");
      }
      uint64_t covered = 0;
      for (size_t i = 0; i < bytes; i += 5) {
        covered += uint64_t{in.data()->Get(static_cast<flatbuffers::uoffset_t>(i))} + 1;
      }
      if (covered != pixels) {
        return Status::failure(where + ": RLE runs cover " + num(covered) + " pixels, expected " +
                               num(pixels));
      }
      break;
    }
    case fb::ImageEncoding::alpha_runs:
      if (!validAlphaRuns(std::span<const uint8_t>(in.data() ? in.data()->data() : nullptr, bytes),
                          pixels)) {
        return Status::failure(where + ": alpha-run data of " + num(bytes) +
                               " bytes does not cover exactly " + num(pixels) + " pixels");
      }
      break;
    case fb::ImageEncoding::alpha_runs_zstd: {
      // Handed on as the alpha runs it holds.
      std::string why;
      if (!decompressAlphaRuns({in.data() ? in.data()->data() : nullptr, bytes}, pixels, out.data,
                               why))
        return Status::failure(where + ": " + why);
      out.view = in.view();
      out.width = in.width();
      out.height = in.height();
      out.encoding = ImageEncoding::kAlphaRuns;
      return {};
    }
    default:
      return Status::failure(where + ": unknown encoding " +
                             num(static_cast<uint8_t>(in.encoding())));
  }
  out.view = in.view();
  out.width = in.width();
  out.height = in.height();
  out.encoding = static_cast<ImageEncoding>(in.encoding());
  out.data = copyVector(in.data());
  return {};
}

Status decodeFrameTimestamps(const fb::FrameTimestamps& in, const MessageLimits& limits,
                             FrameTimestampsData& out) {
  const size_t stages = sizeOf(in.stages());
  if (stages > static_cast<size_t>(limits.max_stages)) {
    return Status::failure("frame timestamps: " + num(stages) + " stages, at most " +
                           num(limits.max_stages) + " allowed");
  }
  for (size_t i = 0; i < stages; ++i) {
    const fb::StageTime* s = in.stages()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (s == nullptr) return Status::failure("frame timestamps: stage " + num(i) + " is missing");
    if (Status c = checkString(s->stage(), "frame timestamps: stage name", limits); !c.ok()) {
      return c;
    }
    out.stages.push_back({copyString(s->stage()), s->ns()});
  }
  return {};
}

template <typename Table, typename Data, typename Decode>
Status decodeBody(const Table* table, const char* name, const MessageLimits& limits, Decode decode,
                  MessageBody& body) {
  if (table == nullptr) return Status::failure(std::string(name) + ": the body is missing");
  Data data;
  Status c = decode(*table, limits, data);
  if (c.ok()) body = std::move(data);
  return c;
}

DecodeResult failure(std::string reason) {
  DecodeResult r;
  r.status = Status::failure(std::move(reason));
  return r;
}

}  // namespace

DecodeResult decodeMessage(const uint8_t* data, size_t size, const MessageLimits& limits) {
  if (data == nullptr || size == 0) return failure("empty message");
  if (size > limits.max_bytes || size >= FLATBUFFERS_MAX_BUFFER_SIZE) {
    return failure("message of " + num(size) + " bytes, at most " + num(limits.max_bytes) +
                   " allowed");
  }
  if (size < sizeof(flatbuffers::uoffset_t) + flatbuffers::kFileIdentifierLength ||
      !flatbuffers::BufferHasIdentifier(data, fb::EnvelopeIdentifier())) {
    return failure("not a Lumistage message (" + num(size) + " bytes without the LUMI identifier)");
  }
  // Depth: envelope > body > vector > table > string is 5 deep; tables: a heartbeat or masks of
  // max_cameras each, with room to spare.
  flatbuffers::Verifier verifier(
      data, size, /*max_depth=*/16,
      /*max_tables=*/
      static_cast<flatbuffers::uoffset_t>(4 * (limits.max_cameras + limits.max_stages) + 16));
  if (!fb::VerifyEnvelopeBuffer(verifier)) {
    return failure("malformed message of " + num(size) +
                   " bytes (FlatBuffers verifier refused it)");
  }
  const fb::Envelope* envelope = fb::GetEnvelope(data);
  if (envelope->version() != kProtocolVersion) {
    return failure("protocol version " + num(envelope->version()) + ", expected " +
                   num(kProtocolVersion));
  }
  if (Status c = checkString(envelope->sender(), "sender", limits); !c.ok()) {
    return failure(c.error());
  }
  Message message;
  message.version = envelope->version();
  message.sender = copyString(envelope->sender());
  message.frame_id = envelope->frame_id();
  message.sent_ns = envelope->sent_ns();
  Status c;
  switch (envelope->body_type()) {
    case fb::Body::Hello:
      c = decodeBody<fb::Hello, HelloData>(envelope->body_as_Hello(), "hello", limits, decodeHello,
                                           message.body);
      break;
    case fb::Body::Heartbeat:
      c = decodeBody<fb::Heartbeat, HeartbeatData>(envelope->body_as_Heartbeat(), "heartbeat",
                                                   limits, decodeHeartbeat, message.body);
      break;
    case fb::Body::Silhouettes:
      c = decodeBody<fb::Silhouettes, SilhouettesData>(
          envelope->body_as_Silhouettes(), "silhouettes", limits, decodeSilhouettes, message.body);
      break;
    case fb::Body::Pose:
      c = decodeBody<fb::Pose, PoseData>(envelope->body_as_Pose(), "pose", limits, decodePose,
                                         message.body);
      break;
    case fb::Body::VertexStatistics:
      c = decodeBody<fb::VertexStatistics, VertexStatisticsData>(
          envelope->body_as_VertexStatistics(), "vertex statistics", limits, decodeVertexStatistics,
          message.body);
      break;
    case fb::Body::Offsets:
      c = decodeBody<fb::Offsets, OffsetsData>(envelope->body_as_Offsets(), "offsets", limits,
                                               decodeOffsets, message.body);
      break;
    case fb::Body::PartialImage:
      c = decodeBody<fb::PartialImage, PartialImageData>(envelope->body_as_PartialImage(),
                                                         "partial image", limits,
                                                         decodePartialImage, message.body);
      break;
    case fb::Body::FrameTimestamps:
      c = decodeBody<fb::FrameTimestamps, FrameTimestampsData>(envelope->body_as_FrameTimestamps(),
                                                               "frame timestamps", limits,
                                                               decodeFrameTimestamps, message.body);
      break;
    case fb::Body::View:
      c = decodeBody<fb::View, ViewData>(envelope->body_as_View(), "view", limits, decodeView,
                                         message.body);
      break;
    case fb::Body::Record:
      c = decodeBody<fb::Record, RecordData>(envelope->body_as_Record(), "record", limits,
                                             decodeRecord, message.body);
      break;
    case fb::Body::FrameIds:
      c = decodeBody<fb::FrameIds, FrameIdsData>(envelope->body_as_FrameIds(), "frame ids", limits,
                                                 decodeFrameIds, message.body);
      break;
    case fb::Body::NONE:
      c = Status::failure("message without a body");
      break;
    default:
      c = Status::failure("unknown message type " +
                          num(static_cast<uint8_t>(envelope->body_type())));
      break;
  }
  if (!c.ok()) return failure(c.error());
  DecodeResult result;
  result.message = std::move(message);
  return result;
}

std::vector<uint8_t> encodeMessage(const Message& message) {
  flatbuffers::FlatBufferBuilder builder(1024);
  encodeInto(builder, message);
  return {builder.GetBufferPointer(), builder.GetBufferPointer() + builder.GetSize()};
}

MessageEncoder::MessageEncoder() : builder_(std::make_unique<flatbuffers::FlatBufferBuilder>()) {}
MessageEncoder::~MessageEncoder() = default;

std::span<const uint8_t> MessageEncoder::encode(const Message& message) {
  encodeInto(*builder_, message);
  return {builder_->GetBufferPointer(), builder_->GetSize()};
}

}  // namespace lumistage
