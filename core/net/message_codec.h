#pragma once

// The FlatBuffers wire form of the messages between camera nodes and the studio
// (core/net/messages.fbs; the plain structs are core/net/message_types.h's). The decoder is the
// one door through which bytes from the network become data: it verifies before it reads, and
// copies out so that nothing refers to the buffer afterwards. Besides the generated header it uses
// only core/base/names, core/imaging/partial_image_codec and core/refine/refinement_statistics, so
// that the fuzz target builds from those files alone.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/status.h"
#include "core/net/message_types.h"

namespace flatbuffers {
class FlatBufferBuilder;
}

namespace lumistage {

// Whether `take` can name a take (a folder on every node): a valid name as cameras and nodes have
// (core/base/names.h); fails saying why not.
Status checkTakeName(std::string_view take);

// What a node's messages to the studio are sized by: the rig, the refinement and the views.
struct NodeMessageSizes {
  int cameras = 0;                 // the rig's (a bound on any one node's)
  int64_t camera_pixels = 0;       // the largest camera's width x height
  int silhouette_step = 1;         // silhouette cells of step x step pixels
  int64_t statistics_samples = 0;  // points refined x offset levels
  int64_t view_pixels = 0;         // the largest view the nodes render
};

// The largest message a node may legitimately send for those sizes, in bytes on the wire: its
// silhouettes (with the actor's colours in every cell), its refinement statistics (zstd's bound of
// their largest packed form, which bounds the packed form too), a partial image of the largest view
// in any encoding (5 bytes a pixel at worst, RLE of no two equal pixels), a heartbeat or frame
// timestamps with every string at `limits`' longest; each with the FlatBuffers tables around it.
size_t largestNodeMessage(const NodeMessageSizes& sizes, const MessageLimits& limits = {});

// Either a message or why the bytes were refused.
struct DecodeResult {
  std::optional<Message> message;
  Status status;  // ok with a message; else why there is none
  bool ok() const { return message.has_value(); }
  const std::string& error() const { return status.error(); }
};

// Verifies and copies out one buffer. Never throws on bad input (only std::bad_alloc, which
// max_bytes bounds), never reads outside [data, data + size).
DecodeResult decodeMessage(const uint8_t* data, size_t size, const MessageLimits& limits = {});

// The wire form of a message. Encoding never validates: a sender that builds nonsense finds out
// from the receiver's reason, as a broken peer would.
std::vector<uint8_t> encodeMessage(const Message& message);

// Encodes into a builder it keeps, so that a node sending every frame allocates only while
// warming up. The span is valid until the next encode() or the encoder's end.
class MessageEncoder {
 public:
  MessageEncoder();
  ~MessageEncoder();
  MessageEncoder(const MessageEncoder&) = delete;
  MessageEncoder& operator=(const MessageEncoder&) = delete;
  std::span<const uint8_t> encode(const Message& message);

 private:
  std::unique_ptr<flatbuffers::FlatBufferBuilder> builder_;
};

// The name of the body's type, for logs ("heartbeat", "vertex statistics", ...).
const char* messageTypeName(const MessageBody& body);

}  // namespace lumistage
