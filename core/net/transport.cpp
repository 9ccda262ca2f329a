#include "core/net/transport.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <zmq.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <deque>
#include <iterator>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "core/base/error.h"
#include "core/base/names.h"

namespace lumistage {

namespace {

// Logging every bad message of a babbling peer would drown the log: the first few, then one in
// a thousand.
bool worthLogging(int64_t count) {
  return count <= 10 || count % 1000 == 0;
}

// The IP address of the peer of socket `fd`, in words; empty when it cannot be told.
std::string peerAddress(int fd) {
  sockaddr_storage peer{};
  socklen_t length = sizeof peer;
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &length) != 0) return {};
  char text[INET6_ADDRSTRLEN] = {};
  const void* address = nullptr;
  if (peer.ss_family == AF_INET) {
    address = &reinterpret_cast<const sockaddr_in*>(&peer)->sin_addr;
  } else if (peer.ss_family == AF_INET6) {
    address = &reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_addr;
  } else {
    return {};
  }
  return inet_ntop(peer.ss_family, address, text, sizeof text) ? std::string(text) : std::string();
}

void requireKey(std::string_view key, const char* what) {
  if (!isZ85Key(key)) {
    throw Error(fmt::format("{}: expected a 40-character Z85 CURVE key, got {} characters", what,
                            key.size()));
  }
}

// Sends one message (more: more frames follow), waiting at most until `deadline` for room.
bool sendFrame(zmq::socket_t& socket, std::span<const uint8_t> bytes, bool more,
               std::chrono::milliseconds timeout) {
  socket.set(zmq::sockopt::sndtimeo, static_cast<int>(timeout.count()));
  const auto result = socket.send(zmq::const_buffer(bytes.data(), bytes.size()),
                                  more ? zmq::send_flags::sndmore : zmq::send_flags::none);
  return result.has_value();
}

// ZMTP heartbeats on every connection: a peer whose PC lost power or whose cable was pulled never
// closes its TCP connection, and a node would keep queueing for a studio that is gone. A
// connection that answers no ping for kHeartbeatTimeoutMs is closed, and the dealer reconnects by
// itself.
constexpr int kHeartbeatIntervalMs = 1000, kHeartbeatTimeoutMs = 4000;

void setHeartbeats(zmq::socket_t& socket) {
  socket.set(zmq::sockopt::heartbeat_ivl, kHeartbeatIntervalMs);
  socket.set(zmq::sockopt::heartbeat_timeout, kHeartbeatTimeoutMs);
  socket.set(zmq::sockopt::heartbeat_ttl, kHeartbeatTimeoutMs);
}

constexpr int kHandshakeIntervalMs = 5000;
constexpr int kHandshakeLogIntervalMs = 5000;
// A name for each endpoint's monitor socket (inproc names are per context, but say whose).
std::atomic<int> monitor_serial{0};

bool waitReadable(zmq::socket_t& socket, std::chrono::milliseconds timeout, int wake_fd = -1) {
  zmq::pollitem_t items[2] = {{socket.handle(), 0, ZMQ_POLLIN, 0},
                              {nullptr, wake_fd, ZMQ_POLLIN, 0}};
  return zmq::poll(items, wake_fd >= 0 ? 2 : 1, timeout) > 0 &&
         (items[0].revents & ZMQ_POLLIN) != 0;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Studio

struct StudioEndpoint::State {
  StudioEndpointConfig config;
  zmq::context_t context;
  zmq::socket_t router;
  zmq::socket_t zap;       // CURVE only: ZeroMQ asks it about every connecting key (RFC 27)
  zmq::socket_t monitor;   // the router's connection events: accepts, ends, failed handshakes
  std::thread zap_thread;  // serves zap and reads monitor
  std::atomic<bool> stop{false};
  std::unordered_map<std::string, std::string> node_of_key;  // Z85 public key -> node name

  mutable std::mutex mutex;  // guards what other threads read: refusals and counters
  std::deque<Refusal> refusals;
  int64_t refusal_count = 0;
  int64_t handshake_failures = 0;
  std::map<std::string, int64_t> bad_messages;
  // Failed handshakes are logged at most once every kHandshakeLogIntervalMs, with their count.
  int64_t handshake_failures_unlogged = 0;
  std::string last_handshake_failure;
  std::chrono::steady_clock::time_point handshake_logged_at{};
  // The connections open from each address (by the monitor's accept and disconnect events, on the
  // serving thread), and when those over the cap were closed: each makes libzmq report a failed
  // handshake too, which is not counted again.
  std::unordered_map<int, std::string> address_of_fd;
  std::unordered_map<std::string, int> connections_from;
  std::deque<std::chrono::steady_clock::time_point> capped;
  // The connections accepted whose handshake has not ended, oldest first. libzmq tells a
  // handshake's end without its connection: each end is taken as the oldest's (a handshake
  // takes milliseconds), and one that disconnects still here ended without a word.
  std::deque<int> handshaking;

  void serve();
  void answerZap();
  void readMonitor();
  // A connection accepted on socket `fd`: counted against its address, or closed over the cap.
  void accepted(int fd);
  void disconnected(int fd);
  // Whether a failed handshake is that of a connection closed over the cap (and so counted).
  bool wasCapped();
  void handshakeEnded();
  void countHandshakeFailure(std::string reason);
  void logHandshakeFailures(bool force);
  void countBad(const std::string& node, const std::string& reason);
};

void StudioEndpoint::State::serve() {
  while (!stop.load()) {
    try {
      zmq::pollitem_t items[2] = {{monitor.handle(), 0, ZMQ_POLLIN, 0},
                                  {zap ? zap.handle() : nullptr, 0, ZMQ_POLLIN, 0}};
      zmq::poll(items, zap ? 2 : 1, std::chrono::milliseconds(50));
      if ((items[0].revents & ZMQ_POLLIN) != 0) readMonitor();
      if (zap && (items[1].revents & ZMQ_POLLIN) != 0) answerZap();
      logHandshakeFailures(false);
    } catch (const zmq::error_t& e) {
      if (e.num() == ETERM) return;
      if (e.num() != EINTR) spdlog::error("studio: connection handler: {}", e.what());
    }
  }
  logHandshakeFailures(true);
}

// One connection event from the router's monitor (two frames: event and value, address).
void StudioEndpoint::State::readMonitor() {
  std::vector<zmq::message_t> event;
  if (!zmq::recv_multipart(monitor, std::back_inserter(event), zmq::recv_flags::dontwait) ||
      event.size() != 2 || event[0].size() != 6)
    return;
  uint16_t id = 0;
  uint32_t value = 0;
  std::memcpy(&id, event[0].data(), sizeof id);
  std::memcpy(&value, event[0].data<uint8_t>() + 2, sizeof value);
  if (id == ZMQ_EVENT_ACCEPTED) return accepted(int(value));
  if (id == ZMQ_EVENT_DISCONNECTED) return disconnected(int(value));
  if (id == ZMQ_EVENT_HANDSHAKE_SUCCEEDED) return handshakeEnded();
  std::string reason;
  if (id == ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL) {
    reason = value == ZMQ_PROTOCOL_ERROR_ZMTP_CRYPTOGRAPHIC
                 ? "its CURVE handshake did not decrypt (a node that trusts another studio key?)"
             : value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH
                 ? "its security mechanism is not the studio's (plain against CURVE?)"
                 : fmt::format("ZMTP protocol error 0x{:x}", value);
  } else if (id == ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL) {
    if (wasCapped()) return;
    reason = fmt::format("its handshake did not finish ({})", zmq_strerror(int(value)));
  } else {
    handshakeEnded();  // ZMQ_EVENT_HANDSHAKE_FAILED_AUTH: a key refused, counted by answerZap
    return;
  }
  handshakeEnded();
  countHandshakeFailure(std::move(reason));
}

void StudioEndpoint::State::countHandshakeFailure(std::string reason) {
  std::lock_guard lock(mutex);
  ++handshake_failures;
  ++handshake_failures_unlogged;
  last_handshake_failure = std::move(reason);
}

void StudioEndpoint::State::handshakeEnded() {
  if (!handshaking.empty()) handshaking.pop_front();
}

void StudioEndpoint::State::accepted(int fd) {
  std::string address = peerAddress(fd);
  // Gone already (libzmq may drop a connection before this event is read): its handshake still
  // ends in an event or its disconnect.
  if (address.empty()) {
    handshaking.push_back(fd);
    return;
  }
  int& open = connections_from[address];
  if (open < config.max_connections_per_address) {
    ++open;
    address_of_fd[fd] = std::move(address);
    handshaking.push_back(fd);
    return;
  }
  // Shut down, not closed: the descriptor stays libzmq's, whose engine sees the end and closes it.
  ::shutdown(fd, SHUT_RDWR);
  capped.push_back(std::chrono::steady_clock::now());
  std::lock_guard lock(mutex);
  ++refusal_count;
  const std::string text = fmt::format("more than {} connections at once from one address",
                                       config.max_connections_per_address);
  refusals.push_back({address, "", text});
  if (refusals.size() > 64) refusals.pop_front();
  if (worthLogging(refusal_count))
    spdlog::warn("studio: refused a connection from {}: {}", address, text);
}

void StudioEndpoint::State::disconnected(int fd) {
  if (const auto h = std::find(handshaking.begin(), handshaking.end(), fd);
      h != handshaking.end()) {
    // Gone while handshaking, and libzmq said nothing of how: it drops a connection that announces
    // a message over the limit (or breaks the protocol in its framing) without a reason.
    handshaking.erase(h);
    countHandshakeFailure(fmt::format(
        "it was dropped during its handshake without a reason (a message over the {:.1f} MB "
        "limit, or malformed framing?)",
        double(config.limits.max_bytes) / 1e6));
  }
  const auto it = address_of_fd.find(fd);
  if (it == address_of_fd.end()) return;
  if (const auto open = connections_from.find(it->second);
      open != connections_from.end() && --open->second <= 0)
    connections_from.erase(open);
  address_of_fd.erase(it);
}

bool StudioEndpoint::State::wasCapped() {
  // A capped connection's failure follows its shutdown at once; one older than a handshake's
  // whole time (it had finished its handshake before the shutdown) reports none.
  const auto now = std::chrono::steady_clock::now();
  while (!capped.empty() && now - capped.front() > std::chrono::milliseconds(kHandshakeIntervalMs))
    capped.pop_front();
  if (capped.empty()) return false;
  capped.pop_front();
  return true;
}

void StudioEndpoint::State::logHandshakeFailures(bool force) {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(mutex);
  if (handshake_failures_unlogged == 0 ||
      (!force && now - handshake_logged_at < std::chrono::milliseconds(kHandshakeLogIntervalMs)))
    return;
  spdlog::warn("studio: {} connection(s) failed their handshake ({} in all); the last: {}",
               handshake_failures_unlogged, handshake_failures, last_handshake_failure);
  handshake_failures_unlogged = 0;
  handshake_logged_at = now;
}

void StudioEndpoint::State::answerZap() {
  std::vector<zmq::message_t> request;
  if (!zmq::recv_multipart(zap, std::back_inserter(request), zmq::recv_flags::dontwait)) return;
  // version, request id, domain, address, routing id, mechanism, credentials...
  if (request.size() < 6) return;  // not from libzmq; it never sends less
  const std::string address = request[3].to_string();
  const std::string mechanism = request[5].to_string();
  std::string status = "400", text, user;
  if (mechanism != "CURVE" || request.size() < 7 || request[6].size() != 32) {
    text = "mechanism " + mechanism + " refused, CURVE required";
  } else {
    std::array<char, 41> z85{};
    zmq_z85_encode(z85.data(), request[6].data<uint8_t>(), 32);
    const std::string key = z85.data();
    if (const auto it = node_of_key.find(key); it != node_of_key.end()) {
      status = "200";
      text = "OK";
      user = it->second;
    } else {
      text = "node key " + key.substr(0, 8) + " is not authorized";
    }
    if (status != "200") {
      std::lock_guard lock(mutex);
      ++refusal_count;
      refusals.push_back({address, key.substr(0, 8), text});
      if (refusals.size() > 64) refusals.pop_front();
      if (worthLogging(refusal_count)) {
        spdlog::warn("studio: refused a node at {}: {}", address, text);
      }
    }
  }
  const std::string version = request[0].to_string(), id = request[1].to_string();
  const std::array<zmq::const_buffer, 6> reply{zmq::buffer(version), zmq::buffer(id),
                                               zmq::buffer(status),  zmq::buffer(text),
                                               zmq::buffer(user),    zmq::str_buffer("")};
  zmq::send_multipart(zap, reply);
}

void StudioEndpoint::State::countBad(const std::string& node, const std::string& reason) {
  int64_t count;
  {
    std::lock_guard lock(mutex);
    count = ++bad_messages[node];
  }
  if (worthLogging(count)) {
    spdlog::warn("studio: dropped a message from node {} ({} so far): {}", node, count, reason);
  }
}

StudioEndpoint::StudioEndpoint(StudioEndpointConfig config) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.config = std::move(config);
  s.router = zmq::socket_t(s.context, zmq::socket_type::router);
  s.router.set(zmq::sockopt::linger, 0);
  s.router.set(zmq::sockopt::router_mandatory, true);
  setHeartbeats(s.router);
  // A node that comes back under its name (rebooted, its cable plugged in again) takes the name
  // over from its old connection, which may not have timed out yet: a ROUTER otherwise ignores a
  // second connection under a name it holds, and libzmq then reads the node's next message as its
  // name. Under CURVE a message still counts for the node its key names, whatever it calls itself.
  s.router.set(zmq::sockopt::router_handover, true);
  // Oversized messages never reach memory: libzmq drops the connection that announces one, while
  // its handshake is under way too (when a message that size is all a connection may make it
  // buffer: the coordinator sets the limit from the rig, not at 64 MB).
  s.router.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(s.config.limits.max_bytes));
  // A connection that has not finished its handshake in this time is closed (libzmq waits 30 s):
  // a node's handshake takes milliseconds; a hostile one holds its buffers for at most this long.
  s.router.set(zmq::sockopt::handshake_ivl, kHandshakeIntervalMs);
  if (s.config.security == TransportSecurity::kCurve) {
    requireKey(s.config.studio_key.public_key, "studio public key");
    requireKey(s.config.studio_key.secret_key, "studio secret key");
    for (const AuthorizedNode& node : s.config.authorized) {
      requireKey(node.public_key, ("authorized key of node " + node.name).c_str());
      s.node_of_key[node.public_key] = node.name;
    }
    // The handler must be bound before the first handshake, or libzmq admits every key.
    s.zap = zmq::socket_t(s.context, zmq::socket_type::rep);
    s.zap.set(zmq::sockopt::linger, 0);
    s.zap.bind("inproc://zeromq.zap.01");
    s.router.set(zmq::sockopt::curve_server, true);
    s.router.set(zmq::sockopt::curve_secretkey, s.config.studio_key.secret_key);
    s.router.set(zmq::sockopt::zap_domain, "lumistage");
  }
  // Connections accepted and gone, and handshakes that fail (a node trusting another studio key, a
  // plain peer, one that never finishes), are told by the router's monitor, read on the same
  // thread as the ZAP requests.
  const std::string monitor_endpoint =
      fmt::format("inproc://lumistage.studio.monitor.{}", monitor_serial++);
  if (zmq_socket_monitor(s.router.handle(), monitor_endpoint.c_str(),
                         ZMQ_EVENT_ACCEPTED | ZMQ_EVENT_DISCONNECTED |
                             ZMQ_EVENT_HANDSHAKE_SUCCEEDED | ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL |
                             ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                             ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) != 0)
    throw Error(
        fmt::format("studio endpoint: cannot monitor its socket: {}", zmq_strerror(zmq_errno())));
  s.monitor = zmq::socket_t(s.context, zmq::socket_type::pair);
  s.monitor.set(zmq::sockopt::linger, 0);
  s.monitor.connect(monitor_endpoint);
  s.zap_thread = std::thread([&s] { s.serve(); });
  try {
    s.router.bind(s.config.bind);
  } catch (const zmq::error_t& e) {
    s.stop = true;
    if (s.zap_thread.joinable()) s.zap_thread.join();
    throw Error(fmt::format("studio endpoint {}: cannot bind: {}", s.config.bind, e.what()));
  }
  spdlog::info(
      "studio: messages of up to {:.1f} MB taken, handshakes closed after {} s; a connection "
      "announcing a larger message is dropped",
      double(s.config.limits.max_bytes) / 1e6, kHandshakeIntervalMs / 1000);
}

StudioEndpoint::~StudioEndpoint() {
  state_->stop = true;
  if (state_->zap_thread.joinable()) state_->zap_thread.join();
  zmq_socket_monitor(state_->router.handle(), nullptr, 0);
  state_->router.close();
  state_->zap.close();
  state_->monitor.close();
}

std::string StudioEndpoint::endpoint() const {
  return state_->router.get(zmq::sockopt::last_endpoint);
}

std::optional<ReceivedMessage> StudioEndpoint::receive(std::chrono::milliseconds timeout,
                                                       int wake_fd) {
  State& s = *state_;
  try {
    if (!waitReadable(s.router, timeout, wake_fd)) return std::nullopt;
    std::vector<zmq::message_t> frames;
    if (!zmq::recv_multipart(s.router, std::back_inserter(frames), zmq::recv_flags::dontwait)) {
      return std::nullopt;
    }
    ReceivedMessage received;
    received.peer = frames.at(0).to_string();
    received.node = received.peer;
    for (size_t f = 1; f < frames.size(); ++f) received.bytes += frames[f].size();
    if (frames.size() >= 2) {
      // Under CURVE the name comes from the key the handshake proved, not from what the peer
      // calls itself.
      // (zmq_msg_gets, not message_t::gets, which throws when there is no such property.)
      const char* user = zmq_msg_gets(frames[1].handle(), "User-Id");
      if (user != nullptr && *user != '\0') {
        received.node = user;
      }
    }
    if (!isValidName(received.node)) {
      // In plain mode a peer's name is whatever it calls itself: one that is no node name (a line
      // break and a forged log line in it, terminal escapes) is refused, and logged quoted.
      received.node = quotedInput(received.node, 64);
      received.result.status = Status::failure("its name is not a valid node name");
    } else if (frames.size() != 2) {
      received.result.status =
          Status::failure(fmt::format("expected one frame a message, got {}", frames.size() - 1));
    } else {
      received.result = decodeMessage(frames[1].data<uint8_t>(), frames[1].size(), s.config.limits);
    }
    if (!received.result.ok()) s.countBad(received.node, received.result.error());
    return received;
  } catch (const zmq::error_t& e) {
    // A signal (the process being told to stop) interrupts the wait: not a failure.
    if (e.num() != EINTR) spdlog::error("studio: receive failed: {}", e.what());
    return std::nullopt;
  }
}

bool StudioEndpoint::send(const std::string& peer, std::span<const uint8_t> bytes,
                          std::chrono::milliseconds timeout) {
  try {
    const auto* id = reinterpret_cast<const uint8_t*>(peer.data());
    return sendFrame(state_->router, {id, peer.size()}, true, timeout) &&
           sendFrame(state_->router, bytes, false, timeout);
  } catch (const zmq::error_t&) {
    return false;  // EHOSTUNREACH: no such peer (router_mandatory)
  }
}

bool StudioEndpoint::send(const std::string& peer, const Message& message,
                          std::chrono::milliseconds timeout) {
  const std::vector<uint8_t> bytes = encodeMessage(message);
  return send(peer, bytes, timeout);
}

size_t StudioEndpoint::maxMessageBytes() const {
  return state_->config.limits.max_bytes;
}

std::vector<Refusal> StudioEndpoint::refusals() const {
  std::lock_guard lock(state_->mutex);
  return {state_->refusals.begin(), state_->refusals.end()};
}

int64_t StudioEndpoint::refusalCount() const {
  std::lock_guard lock(state_->mutex);
  return state_->refusal_count;
}

int64_t StudioEndpoint::handshakeFailures() const {
  std::lock_guard lock(state_->mutex);
  return state_->handshake_failures;
}

std::map<std::string, int64_t> StudioEndpoint::badMessages() const {
  std::lock_guard lock(state_->mutex);
  return state_->bad_messages;
}

// ---------------------------------------------------------------------------------------------
// Node

struct NodeEndpoint::State {
  NodeEndpointConfig config;
  zmq::context_t context;
  zmq::socket_t dealer;
  std::atomic<int64_t> bad_messages{0};
};

NodeEndpoint::NodeEndpoint(NodeEndpointConfig config) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.config = std::move(config);
  if (s.config.name.empty() || s.config.name.size() > 255) {
    throw Error("node endpoint: the node name must be 1 to 255 bytes");
  }
  s.dealer = zmq::socket_t(s.context, zmq::socket_type::dealer);
  s.dealer.set(zmq::sockopt::linger, 0);
  s.dealer.set(zmq::sockopt::routing_id, s.config.name);
  // Messages wait for an accepted connection instead of piling up for a studio that refused us.
  s.dealer.set(zmq::sockopt::immediate, true);
  setHeartbeats(s.dealer);
  s.dealer.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(s.config.limits.max_bytes));
  if (s.config.security == TransportSecurity::kCurve) {
    requireKey(s.config.node_key.public_key, "node public key");
    requireKey(s.config.node_key.secret_key, "node secret key");
    requireKey(s.config.studio_public_key, "studio public key");
    s.dealer.set(zmq::sockopt::curve_serverkey, s.config.studio_public_key);
    s.dealer.set(zmq::sockopt::curve_publickey, s.config.node_key.public_key);
    s.dealer.set(zmq::sockopt::curve_secretkey, s.config.node_key.secret_key);
  }
  try {
    s.dealer.connect(s.config.connect);
  } catch (const zmq::error_t& e) {
    throw Error(fmt::format("node endpoint {}: cannot connect: {}", s.config.connect, e.what()));
  }
}

NodeEndpoint::~NodeEndpoint() {
  state_->dealer.close();
}

bool NodeEndpoint::send(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout) {
  try {
    return sendFrame(state_->dealer, bytes, false, timeout);
  } catch (const zmq::error_t&) {
    return false;
  }
}

bool NodeEndpoint::send(const Message& message, std::chrono::milliseconds timeout) {
  const std::vector<uint8_t> bytes = encodeMessage(message);
  return send(bytes, timeout);
}

std::optional<DecodeResult> NodeEndpoint::receive(std::chrono::milliseconds timeout, int wake_fd) {
  State& s = *state_;
  try {
    if (!waitReadable(s.dealer, timeout, wake_fd)) return std::nullopt;
    std::vector<zmq::message_t> frames;
    if (!zmq::recv_multipart(s.dealer, std::back_inserter(frames), zmq::recv_flags::dontwait)) {
      return std::nullopt;
    }
    DecodeResult result;
    if (frames.size() != 1) {
      result.status =
          Status::failure(fmt::format("expected one frame a message, got {}", frames.size()));
    } else {
      result = decodeMessage(frames[0].data<uint8_t>(), frames[0].size(), s.config.limits);
    }
    if (!result.ok()) {
      const int64_t count = ++s.bad_messages;
      if (worthLogging(count)) {
        spdlog::warn("node {}: dropped a message from the studio ({} so far): {}", s.config.name,
                     count, result.error());
      }
    }
    return result;
  } catch (const zmq::error_t& e) {
    if (e.num() != EINTR) spdlog::error("node {}: receive failed: {}", s.config.name, e.what());
    return std::nullopt;
  }
}

int64_t NodeEndpoint::badMessages() const {
  return state_->bad_messages.load();
}

}  // namespace lumistage
