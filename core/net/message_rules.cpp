// The codec's rules that need no FlatBuffers (message_codec.h): take names, the largest message a
// node may send, the messages' names.
#include <algorithm>
#include <iterator>
#include <string>

#include "core/base/names.h"
#include "core/net/message_codec.h"
#include "core/refine/refinement_statistics.h"

namespace lumistage {

Status checkTakeName(std::string_view take) {
  if (isValidName(take)) return {};  // the rule of camera and node names; below, why not
  if (take.empty() || take.size() > 64) {
    return Status::failure("take name of " + std::to_string(take.size()) +
                           " characters, expected 1 to 64");
  }
  // Quoted in the message with anything unprintable as '?': it goes to logs as it is.
  std::string shown(take);
  for (char& c : shown) c = (c >= 0x20 && c < 0x7f) ? c : '?';
  if (take.front() == '.' || take.front() == '-')
    return Status::failure("take name '" + shown + "' starts with '" + take.front() + "'");
  return Status::failure("take name '" + shown +
                         "' has a character other than letters, digits, '-', '_' and '.'");
}

size_t largestNodeMessage(const NodeMessageSizes& sizes, const MessageLimits& limits) {
  // An envelope, a body table and a vector's length and padding: a few hundred bytes; a string is
  // its length, its bytes, its terminator and padding.
  const uint64_t table = 256, text = limits.max_string_bytes + 8;
  const uint64_t cameras = uint64_t(std::max(sizes.cameras, 0));
  const uint64_t step = uint64_t(std::max(sizes.silhouette_step, 1));
  const uint64_t cells = uint64_t(std::max<int64_t>(sizes.camera_pixels, 0)) / (step * step);
  // Each mask's bits and, on a frame that carries them, three colour bytes a cell of the actor.
  const uint64_t silhouettes = table + cameras * (2 * table + (cells + 7) / 8 + 3 * cells);
  const uint64_t statistics = table + maxCompressedStatisticsBytes(
                                          uint64_t(std::max<int64_t>(sizes.statistics_samples, 0)));
  const uint64_t image = table + 5 * uint64_t(std::max<int64_t>(sizes.view_pixels, 0));
  const uint64_t heartbeat = table + cameras * (table + 2 * text) + table + 3 * text;
  const uint64_t timestamps = table + uint64_t(std::max(limits.max_stages, 0)) * (table + text);
  const uint64_t hello = table + text + (cameras + 64) * text;
  return size_t(std::max({silhouettes, statistics, image, heartbeat, timestamps, hello}));
}

const char* messageTypeName(const MessageBody& body) {
  static constexpr const char* kNames[] = {
      "hello",         "heartbeat",        "silhouettes", "pose",   "vertex statistics", "offsets",
      "partial image", "frame timestamps", "view",        "record", "frame ids"};
  static_assert(std::size(kNames) == std::variant_size_v<MessageBody>);
  return kNames[body.index()];
}

}  // namespace lumistage
