#include "app/cli/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <string>

namespace lumistage {

void printProgress(const char* what, int done, int total, double ms_per_item) {
  constexpr int kWidth = 30;
  const int filled = total > 0 ? done * kWidth / total : kWidth;
  std::string timing;
  if (ms_per_item >= 0) {
    timing = fmt::format(", {:.0f} ms each, {:.0f} s left", ms_per_item,
                         (total - done) * ms_per_item / 1000.0);
  }
  if (isatty(STDERR_FILENO)) {
    fmt::print(stderr, "\r{} [{}{}] {}/{}{}   ", what, std::string(filled, '#'),
               std::string(kWidth - filled, '.'), done, total, timing);
    if (done == total) fmt::print(stderr, "\n");
  } else if (done == total || (done * 10 / total) != ((done - 1) * 10 / total)) {
    fmt::print(stderr, "{}: {}/{}{}\n", what, done, total, timing);
  }
}

}  // namespace lumistage
