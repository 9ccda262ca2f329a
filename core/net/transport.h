#pragma once

// The sockets between the studio and its camera nodes (ZeroMQ). The studio binds a ROUTER and
// every node connects a DEALER, so the studio can answer each node by name and nodes can come and
// go. Under CURVE (the default) traffic is encrypted and the studio admits only node keys it
// knows (KeyStore's authorized/ folder): others are refused at the handshake and reported.
// Every received payload goes through decodeMessage() before anyone sees it.
//
// Each endpoint is used from one thread (ZeroMQ sockets are not thread-safe); counters and
// refusals may be read from any thread. send/receive wait at most their timeout and never throw.

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/net/curve_keys.h"
#include "core/net/message_codec.h"

namespace lumistage {

// kPlain sends everything in the clear and admits anyone: for a closed lab network or tests, and
// only when asked for by name. Both sides must agree; a plain node cannot talk to a CURVE studio.
enum class TransportSecurity { kCurve, kPlain };

struct StudioEndpointConfig {
  std::string bind = "tcp://*:5570";  // tcp://127.0.0.1:* picks a free port (see endpoint())
  TransportSecurity security = TransportSecurity::kCurve;
  CurveKeyPair studio_key;                 // kCurve only
  std::vector<AuthorizedNode> authorized;  // kCurve only: the node keys admitted
  MessageLimits limits;
  // Connections open at once from one IP address, handshaking or not; one more is closed as it is
  // accepted and counted as a refusal. Every connection may make libzmq buffer a message of
  // limits.max_bytes, so this bounds what one address can make the studio hold. Nodes on one PC
  // share its address: the coordinator raises it to fit the rig's nodes.
  int max_connections_per_address = 16;
};

// A node turned away at the handshake.
struct Refusal {
  std::string address;     // the peer's IP address
  std::string key_prefix;  // first 8 Z85 characters of its public key; empty before a key
  std::string reason;      // "node key abcdefgh is not authorized"
};

struct ReceivedMessage {
  std::string peer;  // the node's routing id: what send() takes to answer it
  std::string node;  // who sent it: the name its CURVE key is authorized under (kPlain: peer)
  size_t bytes = 0;  // its size on the wire, the routing id left out
  DecodeResult result;
};

class StudioEndpoint {
 public:
  // Throws Error naming the address when it cannot bind, or naming the key when it is not valid.
  explicit StudioEndpoint(StudioEndpointConfig config);
  ~StudioEndpoint();
  StudioEndpoint(const StudioEndpoint&) = delete;
  StudioEndpoint& operator=(const StudioEndpoint&) = delete;

  // The bound address with the port resolved, e.g. "tcp://127.0.0.1:40123".
  std::string endpoint() const;

  // The next message from any node, or nothing after `timeout`. A message that fails to decode
  // comes back with its reason (result.ok() false) after it is counted against its node and
  // logged.
  // Also ends the wait when `wake_fd` (>= 0) turns readable (a Wakeup), returning nothing.
  std::optional<ReceivedMessage> receive(std::chrono::milliseconds timeout, int wake_fd = -1);
  // False when the peer is unknown or gone, or its queue stays full for `timeout`.
  bool send(const std::string& peer, std::span<const uint8_t> bytes,
            std::chrono::milliseconds timeout);
  bool send(const std::string& peer, const Message& message, std::chrono::milliseconds timeout);

  // The largest message taken (config.limits.max_bytes): libzmq drops the connection of a peer
  // that announces a larger one, before its handshake is done too.
  size_t maxMessageBytes() const;

  // The latest refusals (at most 64) and how many there were in all: keys refused, and connections
  // over max_connections_per_address.
  std::vector<Refusal> refusals() const;
  int64_t refusalCount() const;
  // Connections whose handshake failed before a key was checked: a node that trusts another
  // studio key, a plain peer at a CURVE studio, garbage, a handshake not done in 5 s, one that
  // announced a message over maxMessageBytes() (libzmq drops it without a reason: counted as a
  // connection gone during its handshake). Logged at most once every 5 s, with their count. (Keys
  // refused, and connections over the cap, are refusalCount().)
  int64_t handshakeFailures() const;
  // Messages dropped as malformed, per node.
  std::map<std::string, int64_t> badMessages() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

struct NodeEndpointConfig {
  std::string connect;  // the studio, e.g. tcp://studio-pc:5570
  std::string name;     // the node's name: its routing id at the studio
  TransportSecurity security = TransportSecurity::kCurve;
  CurveKeyPair node_key;          // kCurve only
  std::string studio_public_key;  // kCurve only
  MessageLimits limits;
};

class NodeEndpoint {
 public:
  // Throws Error when a key is not valid or the address cannot be used.
  explicit NodeEndpoint(NodeEndpointConfig config);
  ~NodeEndpoint();
  NodeEndpoint(const NodeEndpoint&) = delete;
  NodeEndpoint& operator=(const NodeEndpoint&) = delete;

  // False when no accepted connection to the studio takes the message within `timeout`: the
  // studio is down, unreachable, or refused this node's key. Nothing is queued for later.
  bool send(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout);
  bool send(const Message& message, std::chrono::milliseconds timeout);
  // The next message from the studio, decoded or with the reason it was dropped. Waits at most
  // `timeout`, and no longer than until `wake_fd` (a file descriptor, when not -1) is readable.
  std::optional<DecodeResult> receive(std::chrono::milliseconds timeout, int wake_fd = -1);
  int64_t badMessages() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace lumistage
