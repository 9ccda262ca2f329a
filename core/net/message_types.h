#pragma once

// The messages between camera nodes and the studio as plain structs: what each side sends and
// receives, with no wire form. Their FlatBuffers form is core/net/message_codec.h's; code that only
// holds or builds messages (the renderer's views, the posed body, the live feeds) includes this.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <variant>
#include <vector>

namespace lumistage {

// Raised whenever a table changes in a way an older peer would misread; every message carries it,
// and one of another version is refused as it is decoded. What each version changed is in
// docs/figures-history.md ("The wire protocol's versions").
inline constexpr uint16_t kProtocolVersion = 11;

struct HelloData {
  std::string node_name;
  std::vector<std::string> camera_names;
  uint16_t protocol_version = kProtocolVersion;
  std::vector<std::string> capabilities;
  bool operator==(const HelloData&) const = default;
};

struct CameraHealthData {
  std::string camera;
  int64_t frames = 0;
  int64_t dropped = 0;
  float frame_rate = 0;
  std::string last_error;
  // How its frames are keyed, in words (kKeyedOnGreen, kKeyedFromMasks, kKeyedOnPlate); empty from
  // an older node.
  std::string key = {};
  bool operator==(const CameraHealthData&) const = default;
};
inline constexpr const char* kKeyedOnGreen = "keyed on its green screen";
inline constexpr const char* kKeyedFromMasks = "keyed from the session's masks";
inline constexpr const char* kKeyedOnPlate = "keyed on its clean plate";
inline constexpr const char* kLearningPlate = "learning its clean plate: keep the stage empty";

// Where a node's recording of a take stands (core/pipeline/take_recorder.h).
struct TakeStatusData {
  std::string take;  // empty: no take asked for
  int64_t first_frame = 0, last_frame = 0;
  int64_t written = 0, dropped = 0, bytes = 0;
  bool finished = false;
  std::string error;
  // Free space on the disk the node writes its takes to (whether or not one is recording);
  // -1: unknown (a node without a takes folder, or one that does not say).
  int64_t free_bytes = -1;
  // The disk's name, the same for nodes that write to one disk (nodes on one PC): their takes
  // share its free space.
  std::string disk;
  bool operator==(const TakeStatusData&) const = default;
};

struct HeartbeatData {
  std::vector<CameraHealthData> cameras;
  int64_t bytes_sent = 0;
  float cpu = 0;
  TakeStatusData take;
  bool operator==(const HeartbeatData&) const = default;
};

// One bit a pixel, row-major, pixel i in bit (i % 8) of byte i / 8.
struct SilhouetteMaskData {
  int camera = 0;
  int width = 0;
  int height = 0;
  std::vector<uint8_t> bits;  // (width * height + 7) / 8 bytes
  // The actor's colours, three bytes a set bit in the bits' order (sampleSilhouetteColours); empty
  // on most frames.
  std::vector<uint8_t> colours;
  bool operator==(const SilhouetteMaskData&) const = default;
};

struct SilhouettesData {
  std::vector<SilhouetteMaskData> masks;
  bool operator==(const SilhouettesData&) const = default;
};

struct PoseData {
  float root[3] = {0, 0, 0};  // metres
  std::vector<float> angles;  // three a joint, radians
  float scale = 1;            // of the posed body, about the world origin (posed_body.h)
  bool operator==(const PoseData&) const = default;
};

// A node's refinement statistics: `packed` is their wire form, packed or compressed
// (core/refine/refinement_statistics.h; nodes send it compressed); its header must agree with the
// counts here.
struct VertexStatisticsData {
  uint32_t vertex_count = 0;
  int offset_count = 0;
  std::vector<uint8_t> packed;
  bool operator==(const VertexStatisticsData&) const = default;
};

struct OffsetsData {
  int offset_count = 0;
  std::vector<uint8_t> offsets;  // one a vertex, each < offset_count
  // Which rig cameras see each vertex (bit c: camera c; VertexVisibility): empty, or one a vertex.
  std::vector<uint32_t> visibility;
  bool operator==(const OffsetsData&) const = default;
};

// On the wire alpha runs travel zstd-compressed where that is smaller (messages.fbs); decoded,
// they are alpha runs again.
enum class ImageEncoding : uint8_t { kRawRgba = 0, kRleRgba = 1, kAlphaRuns = 2 };

struct PartialImageData {
  int view = 0;
  int width = 0;
  int height = 0;
  ImageEncoding encoding = ImageEncoding::kRawRgba;
  std::vector<uint8_t> data;
  bool operator==(const PartialImageData&) const = default;
};

struct StageTimeData {
  std::string stage;
  int64_t ns = 0;
  bool operator==(const StageTimeData&) const = default;
};

struct FrameTimestampsData {
  std::vector<StageTimeData> stages;
  bool operator==(const FrameTimestampsData&) const = default;
};

// A virtual camera for the nodes' partial renders: pinhole, x_cam = R x_world + t, R row-major.
struct ViewData {
  int view = 0;
  int width = 0, height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<float> rotation;     // 9
  std::vector<float> translation;  // 3
  std::vector<float> clones;       // 3 a clone: floor offset x, y (m), yaw (rad)
  bool operator==(const ViewData&) const = default;
};

// The studio asks the nodes to record a take: their own cameras' frame sets with ids in
// [first_frame, last_frame], into <takes folder>/<take>/<node>/. An empty take asks for none.
struct RecordData {
  std::string take;
  int64_t first_frame = 0;
  int64_t last_frame = std::numeric_limits<int64_t>::max();
  bool operator==(const RecordData&) const = default;
};

struct FrameIdsData {
  int64_t offset = 0;  // what the node adds to its frame ids from now on
  bool operator==(const FrameIdsData&) const = default;
};

using MessageBody = std::variant<HelloData, HeartbeatData, SilhouettesData, PoseData,
                                 VertexStatisticsData, OffsetsData, PartialImageData,
                                 FrameTimestampsData, ViewData, RecordData, FrameIdsData>;

// The frame ids of a rig's cameras move together, a frame at a time: an id this far or further
// from the newest is a restart (the cameras, the session) or a message not to trust, for the nodes
// and the studio alike.
constexpr int64_t kFrameIdWindow = 300;

struct Message {
  uint16_t version = kProtocolVersion;
  std::string sender;
  int64_t frame_id = -1;
  int64_t sent_ns = 0;
  MessageBody body;
  bool operator==(const Message&) const = default;
};

// What a receiver accepts. Set the counts from the rig and the mesh in use (a studio with 9
// cameras has no business receiving 60 silhouettes); the defaults bound memory, not meaning.
struct MessageLimits {
  size_t max_bytes = size_t{64} << 20;
  int max_cameras = 64;  // per message: names, health entries, masks, camera indices
  uint32_t max_vertices = 200000;
  int max_offsets = 255;  // offset levels of the refinement, one byte
  int max_clones = 64;    // per view
  int max_joints = 128;
  int max_mask_pixels = 1024 * 1024;
  int max_image_pixels = 4096 * 4096;
  int max_view_side = 8192;  // a view's width or height: what every GPU's framebuffer holds
  int max_stages = 64;
  size_t max_string_bytes = 1024;
};

}  // namespace lumistage
