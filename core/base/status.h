#pragma once

#include <string>
#include <utility>

namespace lumistage {

// Whether something that does not throw went well, and if not, why: core/'s one way of saying
// so (Error, thrown, is for I/O and configuration boundaries; docs/architecture.md, "Errors").
// The reason is in words, as an Error's message is: what, where, what was expected. An ok Status
// holds no text and costs no allocation, so hot paths and decoders of untrusted bytes return it
// freely; a value that may be missing for a reason comes beside one (DecodeResult). Objects whose
// work can fail later, in the background (a recorder, a live feed, a file written as it goes),
// keep one and give it by status().
class [[nodiscard]] Status {
 public:
  Status() = default;  // ok
  // A failure; `reason` is not empty.
  static Status failure(std::string reason) {
    Status s;
    s.reason_ = reason.empty() ? std::string("failed (no reason given)") : std::move(reason);
    return s;
  }
  bool ok() const { return reason_.empty(); }
  // Why it failed; empty when ok.
  const std::string& error() const { return reason_; }

 private:
  std::string reason_;
};

}  // namespace lumistage
