#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/pipeline/bounded_queue.h"

namespace lumistage {

// When a frame entered and left each stage: latency per stage and end to end, measured.
struct FrameTrace {
  int64_t frame_id = -1;
  int64_t submitted_ns = 0;  // steady clock, when the frame entered the pipeline
  struct Stamp {
    int stage = -1;
    int64_t start_ns = 0, end_ns = 0;
  };
  std::vector<Stamp> stamps;
};

struct StageStats {
  std::string name;
  int64_t frames = 0;    // processed
  int64_t dropped = 0;   // pushed out of the stage's input queue: the stage fell behind
  int64_t rejected = 0;  // the stage itself let the frame go (e.g. a deadline missed)
  double ms_mean = 0, ms_p50 = 0, ms_p95 = 0;
};

struct PipelineStats {
  std::vector<StageStats> stages;
  int64_t frames_out = 0;
  double latency_ms_p50 = 0, latency_ms_p95 = 0;  // submit to output
  double fps = 0;                                 // output rate since start()
  int max_in_flight = 0;                          // most frames inside the pipeline at once
};

int64_t steadyNowNs();
// The wall clock (CLOCK_REALTIME), in nanoseconds: what a node's capture time and the studio's
// latency are measured on, since the node and the studio may be different PCs, whose steady
// clocks count from their own boots; a stage's PCs keep their wall clocks in step (chrony, PTP).
int64_t wallNowNs();

// The latest samples of a measurement (a ring of fixed size), so that figures follow the recent
// past and memory stays bounded on a run of hours.
class RecentSamples {
 public:
  explicit RecentSamples(size_t capacity = 2048) : capacity_(capacity) {
    values_.reserve(capacity);
  }
  void add(double v) {
    if (values_.size() < capacity_) {
      values_.push_back(v);
    } else {
      values_[next_] = v;
      next_ = (next_ + 1) % capacity_;
    }
  }
  const std::vector<double>& values() const { return values_; }

 private:
  size_t capacity_, next_ = 0;
  std::vector<double> values_;
};
// The q-th quantile (0..1) of `values` (modified: partially sorted).
double quantile(std::vector<double>& values, double q);
// The rate of events at the steady-clock times `times_ns` (any order): (n - 1) over the time from
// the first to the last, a second; 0 for fewer than two or no time between them.
double eventsPerSecond(const std::vector<double>& times_ns);

// Stages on their own threads, joined by bounded queues (see BoundedQueue): while one stage works
// on frame f, the stage before it works on f+1 and the one after on f-1, as in the paper's
// pipeline of capture, motion capture, refinement and rendering. `Frame` must have a public
// `FrameTrace trace`. A stage returns false to let a frame go (counted as rejected).
template <typename Frame>
class Pipeline {
 public:
  using Stage = std::function<bool(Frame&)>;

  void addStage(std::string name, Stage work, size_t input_capacity = 2) {
    stages_.push_back(
        std::make_unique<StageState>(std::move(name), std::move(work), input_capacity));
  }

  void start() {
    output_ = std::make_unique<BoundedQueue<Frame>>(output_capacity_);
    start_ns_ = steadyNowNs();
    for (size_t s = 0; s < stages_.size(); ++s)
      stages_[s]->thread = std::thread([this, s] { run(s); });
  }

  // Into the first stage; the oldest waiting frame is dropped when it is still busy.
  void submit(Frame frame) {
    frame.trace.submitted_ns = steadyNowNs();
    frame.trace.stamps.clear();
    in_flight_enter();
    if (stages_.front()->input.push(std::move(frame))) in_flight_leave();
  }

  // The next frame out of the last stage.
  std::optional<Frame> next(std::chrono::milliseconds timeout) {
    std::optional<Frame> frame = output_->pop(timeout);
    if (frame) {
      std::lock_guard lock(mutex_);
      latencies_ms_.add((steadyNowNs() - frame->trace.submitted_ns) / 1e6);
      ++frames_out_;
      last_out_ns_ = steadyNowNs();
    }
    return frame;
  }

  // Stops every stage after the frame it is working on; frames still queued are dropped.
  void stop() {
    for (auto& s : stages_) s->input.close();
    for (auto& s : stages_) {
      if (s->thread.joinable()) s->thread.join();
    }
    if (output_) output_->close();
  }

  ~Pipeline() { stop(); }

  PipelineStats stats() const {
    std::lock_guard lock(mutex_);
    PipelineStats out;
    for (const auto& s : stages_) {
      StageStats st;
      st.name = s->name;
      st.frames = s->frames;
      st.dropped = s->input.drops();
      st.rejected = s->rejected;
      std::vector<double> ms = s->ms.values();
      double sum = 0;
      for (double v : ms) sum += v;
      st.ms_mean = ms.empty() ? 0 : sum / ms.size();
      st.ms_p50 = quantile(ms, 0.5);
      st.ms_p95 = quantile(ms, 0.95);
      out.stages.push_back(st);
    }
    std::vector<double> latencies = latencies_ms_.values();
    out.frames_out = frames_out_;
    out.latency_ms_p50 = quantile(latencies, 0.5);
    out.latency_ms_p95 = quantile(latencies, 0.95);
    out.fps = frames_out_ > 1 && last_out_ns_ > start_ns_
                  ? frames_out_ / ((last_out_ns_ - start_ns_) / 1e9)
                  : 0;
    out.max_in_flight = max_in_flight_;
    return out;
  }

 private:
  struct StageState {
    StageState(std::string n, Stage w, size_t capacity)
        : name(std::move(n)), work(std::move(w)), input(capacity) {}
    std::string name;
    Stage work;
    BoundedQueue<Frame> input;
    std::thread thread;
    int64_t frames = 0, rejected = 0;  // guarded by Pipeline::mutex_
    RecentSamples ms;
  };

  void run(size_t s) {
    StageState& stage = *stages_[s];
    while (true) {
      std::optional<Frame> frame = stage.input.pop(std::chrono::milliseconds(100));
      if (!frame) {
        if (stage.input.closed()) return;
        continue;
      }
      const int64_t start = steadyNowNs();
      const bool keep = stage.work(*frame);
      const int64_t end = steadyNowNs();
      frame->trace.stamps.push_back({static_cast<int>(s), start, end});
      {
        std::lock_guard lock(mutex_);
        ++stage.frames;
        stage.ms.add((end - start) / 1e6);
        if (!keep) ++stage.rejected;
      }
      if (!keep) {
        in_flight_leave();
        continue;
      }
      BoundedQueue<Frame>& next = s + 1 < stages_.size() ? stages_[s + 1]->input : *output_;
      if (next.push(std::move(*frame))) in_flight_leave();  // the frame pushed out leaves
      if (s + 1 == stages_.size()) in_flight_leave();       // the output is outside the pipeline
    }
  }

  void in_flight_enter() {
    const int now = ++in_flight_;
    std::lock_guard lock(mutex_);
    if (now > max_in_flight_) max_in_flight_ = now;
  }
  void in_flight_leave() { --in_flight_; }

  std::vector<std::unique_ptr<StageState>> stages_;
  std::unique_ptr<BoundedQueue<Frame>> output_;
  size_t output_capacity_ = 4;
  mutable std::mutex mutex_;
  RecentSamples latencies_ms_;
  int64_t frames_out_ = 0, start_ns_ = 0, last_out_ns_ = 0;
  std::atomic<int> in_flight_{0};
  int max_in_flight_ = 0;
};

}  // namespace lumistage
