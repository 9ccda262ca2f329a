// The studio coordinator's frame ids (StudioCoordinator, studio_coordinator.h): which node's ids
// are accepted, the id of an instant, and a node whose cameras restarted alone told to follow the
// others.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <limits>
#include <utility>

#include "core/pipeline/studio_coordinator.h"

namespace lumistage {

bool StudioCoordinator::acceptFrameId(NodeState& node, int64_t frame_id) {
  // Ids beyond half the range leave no room to count on (takes start ahead of the newest).
  if (frame_id < 0 || frame_id > std::numeric_limits<int64_t>::max() / 2) return false;
  node.newest_frame = frame_id;
  const auto near = [](int64_t a, int64_t b) { return std::abs(a - b) <= kFrameIdWindow; };
  if (newest_seen_ < 0 || near(frame_id, newest_seen_)) {
    node.told_frame_id = false;
    node.refused_since_ns = 0;
    node.times_told = 0;
    // The frame's first arrival (a straggler of an older id, 64 or more back, leaves the slot
    // alone), and how far behind it this node's silhouettes come: its usual lag.
    auto& [id, arrived_ns] = instants_[size_t(frame_id) % kInstants];
    if (frame_id > id) id = frame_id, arrived_ns = node.last_ns;
    if (id == frame_id) {
      const int64_t lag = node.last_ns - arrived_ns;
      node.lag_ns = node.lag_ns == 0 ? lag : (7 * node.lag_ns + lag) / 8;
    }
    return true;
  }
  // The nodes that vote: those frames wait for, and this one (whose silhouettes, refused, no longer
  // make it one of them after a while: two nodes, one silent, could then never move).
  int live = 0, with_it = 0;
  int64_t oldest_with_it = frame_id;
  for (const auto& [name, n] : nodes_) {
    if (&n != &node && !awaited(n)) continue;
    ++live;
    if (n.newest_frame >= 0 && near(n.newest_frame, frame_id)) {
      ++with_it;
      oldest_with_it = std::min(oldest_with_it, n.newest_frame);
    }
  }
  if (2 * with_it <= live) {
    if (!node.told_frame_id) {
      node.told_frame_id = true;
      spdlog::warn(
          "node {}: silhouettes of frame {}, {} frames from the newest the studio has seen ({}): "
          "not used unless most nodes' frame ids move there too",
          node.report.name, frame_id, frame_id - newest_seen_, newest_seen_);
    }
    followLoneNode(node, frame_id);
    return false;
  }
  spdlog::warn("the cameras' frame ids moved from {} to {} on {} of {} nodes: following them",
               newest_seen_, frame_id, with_it, live);
  // The frames in flight belong to the old count; the poses still being fitted for them find no
  // frame to go to.
  for (auto it = frames_.begin(); it != frames_.end();) {
    if (counting_) ++frames_overtaken_;
    it = retireFrame(it);
  }
  refused_.fill(-1);
  newest_done_ = oldest_with_it - 1;
  newest_seen_ = frame_id;
  for (auto& [name, n] : nodes_) n.told_frame_id = false;
  return true;
}

int64_t StudioCoordinator::idArrivingAt(int64_t arrived_ns) const {
  const std::pair<int64_t, int64_t>*oldest = nullptr, *newest = nullptr, *nearest = nullptr;
  for (const auto& instant : instants_) {
    if (instant.first < 0 || std::abs(instant.first - newest_seen_) > kInstants) continue;
    if (!oldest || instant.first < oldest->first) oldest = &instant;
    if (!newest || instant.first > newest->first) newest = &instant;
    if (!nearest || std::abs(instant.second - arrived_ns) < std::abs(nearest->second - arrived_ns))
      nearest = &instant;
  }
  if (!nearest || newest->first - oldest->first < kInstants / 4) return -1;
  const double period =
      double(newest->second - oldest->second) / double(newest->first - oldest->first);
  if (period <= 0) return -1;
  const double frames = double(arrived_ns - nearest->second) / period;
  const double whole = std::round(frames);
  if (std::abs(frames - whole) > 0.25 || std::abs(whole) > kInstants) return -1;
  return nearest->first + int64_t(whole);
}

void StudioCoordinator::followLoneNode(NodeState& node, int64_t frame_id) {
  const int64_t now = node.last_ns;
  if (node.refused_since_ns == 0) node.refused_since_ns = now;
  // Its silhouettes of an instant come its usual lag behind the first of that instant's.
  const int64_t id = idArrivingAt(now - node.lag_ns);
  const int64_t shift = id >= 0 ? id - frame_id : 0;
  node.agreeing = shift != 0 && shift == node.suggested_shift ? node.agreeing + 1 : 0;
  node.suggested_shift = shift;
  const int64_t wait = std::chrono::nanoseconds(kFollowAfter).count();
  if (node.agreeing < kAgreeing || now - node.refused_since_ns < wait ||
      now - node.frame_ids_told_ns < wait || node.peer.empty() || node.times_told > kTimesTold)
    return;
  node.frame_ids_told_ns = now;
  if (++node.times_told > kTimesTold) {  // it keeps its ids (a recording's, an older node)
    spdlog::warn(
        "node {}: its frame ids stay {} from the other nodes' after being told {} times: "
        "not told again; its cameras are left out until they meet",
        node.report.name, shift, kTimesTold);
    return;
  }
  Message message;
  message.sender = "studio";
  message.sent_ns = steadyNowNs();
  message.body = FrameIdsData{shift};
  spdlog::warn(
      "node {}: its frame ids lie {} from the other nodes' for the same instants (its cameras "
      "restarted alone?): told to move them",
      node.report.name, shift);
  endpoint_.send(node.peer, encoder_.encode(message), std::chrono::milliseconds(5));
}

}  // namespace lumistage
