#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

namespace lumistage {

// The queue between two pipeline stages. When it is full a new item pushes the oldest out
// (counted): a stage that falls behind loses frames instead of making every later frame later.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(capacity > 0 ? capacity : 1) {}

  // Adds an item. Returns the item it pushed out, if any (for its buffers to be reused).
  std::optional<T> push(T item) {
    std::optional<T> dropped;
    {
      std::lock_guard lock(mutex_);
      if (closed_) return item;
      if (items_.size() >= capacity_) {
        dropped = std::move(items_.front());
        items_.pop_front();
        ++drops_;
      }
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
    return dropped;
  }

  // The oldest item, waiting at most `timeout`; empty on timeout, or once closed and drained.
  std::optional<T> pop(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_; }))
      return std::nullopt;
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }

  // Wakes every waiter; later pushes are refused (returned as dropped), pops drain what is left.
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }
  size_t size() const {
    std::lock_guard lock(mutex_);
    return items_.size();
  }
  int64_t drops() const {
    std::lock_guard lock(mutex_);
    return drops_;
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> items_;
  bool closed_ = false;
  int64_t drops_ = 0;
};

}  // namespace lumistage
