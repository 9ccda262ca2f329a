#pragma once

// A liblo OSC server on a thread of its own, as a VMC receiver (VSeeFace, EVMC4U) is one: it
// keeps every bundle that arrives, each message's address and arguments. The tests send it only
// from 127.0.0.1 (liblo 0.31 binds a unicast server to every interface, on a port the system
// picks).
#include <lo/lo.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <string>
#include <variant>
#include <vector>

namespace lumistage::testing {

struct OscMessage {
  std::string path, types;
  std::vector<std::variant<std::string, float, int>> args;
  std::string text(size_t k) const { return std::get<std::string>(args.at(k)); }
  float number(size_t k) const { return std::get<float>(args.at(k)); }
  int integer(size_t k) const { return std::get<int>(args.at(k)); }
};
using OscBundle = std::vector<OscMessage>;

class OscReceiver {
 public:
  OscReceiver() {
    server_ = lo_server_thread_new_with_proto(nullptr, LO_UDP, &OscReceiver::onError);
    if (!server_) return;  // port() 0: the test says so
    lo_server_thread_add_method(server_, nullptr, nullptr, &OscReceiver::onMessage, this);
    lo_server_add_bundle_handlers(lo_server_thread_get_server(server_), &OscReceiver::onStart,
                                  &OscReceiver::onEnd, this);
    lo_server_thread_start(server_);
  }
  ~OscReceiver() {
    if (server_) lo_server_thread_free(server_);  // stops its thread
  }
  OscReceiver(const OscReceiver&) = delete;
  OscReceiver& operator=(const OscReceiver&) = delete;

  int port() const { return server_ ? lo_server_thread_get_port(server_) : 0; }

  // Waits for `count` bundles in all (at most `patience`: a bound for a broken run, not a timing
  // that is asserted) and returns those received.
  std::vector<OscBundle> waitForBundles(size_t count,
                                        std::chrono::seconds patience = std::chrono::seconds(20)) {
    std::unique_lock lock(mutex_);
    arrived_.wait_for(lock, patience, [&] { return bundles_.size() >= count; });
    return bundles_;
  }
  std::vector<OscBundle> bundles() {
    std::lock_guard lock(mutex_);
    return bundles_;
  }
  // Messages that came outside any bundle.
  size_t loose() {
    std::lock_guard lock(mutex_);
    return loose_;
  }

 private:
  static void onError(int number, const char* message, const char* where) {
    std::fprintf(stderr, "liblo error %d: %s at %s\n", number, message ? message : "",
                 where ? where : "");
  }
  static int onStart(lo_timetag, void* self) {
    static_cast<OscReceiver*>(self)->open_ = OscBundle();
    static_cast<OscReceiver*>(self)->in_bundle_ = true;
    return 0;
  }
  static int onEnd(void* data) {
    auto* self = static_cast<OscReceiver*>(data);
    {
      std::lock_guard lock(self->mutex_);
      self->bundles_.push_back(std::move(self->open_));
    }
    self->in_bundle_ = false;
    self->arrived_.notify_all();
    return 0;
  }
  static int onMessage(const char* path, const char* types, lo_arg** argv, int argc, lo_message,
                       void* data) {
    auto* self = static_cast<OscReceiver*>(data);
    OscMessage message{path, types, {}};
    for (int k = 0; k < argc; ++k) {
      switch (types[k]) {
        case LO_STRING:
          message.args.emplace_back(std::string(&argv[k]->s));
          break;
        case LO_FLOAT:
          message.args.emplace_back(argv[k]->f);
          break;
        case LO_INT32:
          message.args.emplace_back(int(argv[k]->i));
          break;
        default:
          message.args.emplace_back(std::string("?"));
      }
    }
    if (self->in_bundle_) {
      self->open_.push_back(std::move(message));
    } else {
      std::lock_guard lock(self->mutex_);
      ++self->loose_;
    }
    return 0;
  }

  lo_server_thread server_ = nullptr;
  // The server's thread alone touches these two.
  OscBundle open_;
  bool in_bundle_ = false;
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<OscBundle> bundles_;
  size_t loose_ = 0;
};

}  // namespace lumistage::testing
