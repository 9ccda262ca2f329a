#include "app/cli/run_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kBlue(200, 110, 30), kOrange(30, 130, 240),
    kGreen(60, 150, 60);

void text(cv::Mat& image, const std::string& s, cv::Point at, double scale = 0.5,
          cv::Scalar colour = kInk) {
  cv::putText(image, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

// A "nice" axis step for a range: 1, 2 or 5 times a power of ten, about `ticks` steps.
double niceStep(double range, int ticks) {
  const double raw = std::max(range, 1e-9) / ticks;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw) return m * power;
  return 10 * power;
}

struct Panel {
  cv::Rect box;
  double x_max, y_max;
  cv::Point at(double x, double y) const {
    return {box.x + int(std::lround(x / x_max * box.width)),
            box.y + box.height - int(std::lround(std::min(y, y_max) / y_max * box.height))};
  }
};

Panel drawPanel(cv::Mat& image, cv::Rect box, double x_max, double y_max, const std::string& title,
                const std::string& y_unit) {
  Panel p{box, std::max(x_max, 1e-6), std::max(y_max, 1e-6)};
  const double y_step = niceStep(p.y_max, 5), x_step = niceStep(p.x_max, 10);
  for (double y = 0; y <= p.y_max + 1e-9; y += y_step) {
    cv::line(image, p.at(0, y), p.at(p.x_max, y), kGrid);
    text(image, fmt::format("{:g}", y), p.at(0, y) + cv::Point(-48, 5), 0.4);
  }
  for (double x = 0; x <= p.x_max + 1e-9; x += x_step) {
    cv::line(image, p.at(x, 0), p.at(x, p.y_max), kGrid);
    text(image, fmt::format("{:g}", x), p.at(x, 0) + cv::Point(-8, 18), 0.4);
  }
  cv::rectangle(image, box, kInk);
  text(image, title, {box.x, box.y - 10}, 0.55);
  text(image, y_unit, {box.x - 48, box.y - 10}, 0.4);
  return p;
}

}  // namespace

void writeRunPlot(const RunReport& report, const std::string& caption, const std::string& path) {
  cv::Mat image(720, 1100, CV_8UC3, cv::Scalar(255, 255, 255));
  text(image,
       fmt::format("Lumistage pipeline: {} frames, {:.1f} fps, latency {:.1f} ms median, {:.1f} "
                   "ms 95th percentile",
                   report.frames, report.fps, report.latency_ms_p50, report.latency_ms_p95),
       {30, 32}, 0.62);
  text(image, caption, {30, 56}, 0.45);

  const std::vector<FrameTiming>& t = report.timeline;
  double t_max = 1, latency_max = 1;
  for (const FrameTiming& f : t) {
    t_max = std::max(t_max, f.done_s);
    latency_max = std::max(latency_max, double(f.latency_ms));
  }
  // Latencies: the top panel, scaled to the 99th percentile so one outlier does not flatten it.
  std::vector<double> sorted;
  for (const FrameTiming& f : t) sorted.push_back(f.latency_ms);
  std::sort(sorted.begin(), sorted.end());
  const double l99 = sorted.empty() ? 1 : sorted[size_t(0.99 * (sorted.size() - 1))];
  const Panel latency =
      drawPanel(image, {90, 100, 980, 250}, t_max, std::max(l99, report.latency_ms_p95) * 1.15,
                "latency per frame (node capture to frame done)", "ms");
  for (const FrameTiming& f : t)
    cv::circle(image, latency.at(f.done_s, f.latency_ms), 1, kBlue, -1);
  for (auto [value, colour, name] : {std::tuple{report.latency_ms_p50, kGreen, "median"},
                                     std::tuple{report.latency_ms_p95, kOrange, "95%"}}) {
    cv::line(image, latency.at(0, value), latency.at(t_max, value), colour, 2);
    text(image, fmt::format("{} {:.1f} ms", name, value),
         latency.at(t_max, value) + cv::Point(-130, -6), 0.45, colour);
  }

  // Frame rate over a sliding second.
  std::vector<std::pair<double, double>> rate;
  double rate_max = 1;
  for (size_t i = 0, j = 0; i < t.size(); ++i) {
    while (t[i].done_s - t[j].done_s > 1.0) ++j;
    if (t[i].done_s < 1.0) continue;
    rate.emplace_back(t[i].done_s, double(i - j));
    rate_max = std::max(rate_max, double(i - j));
  }
  const Panel fps = drawPanel(image, {90, 420, 980, 230}, t_max, rate_max * 1.15,
                              "frames done in the last second", "fps");
  for (size_t i = 1; i < rate.size(); ++i)
    cv::line(image, fps.at(rate[i - 1].first, rate[i - 1].second),
             fps.at(rate[i].first, rate[i].second), kBlue, 2, cv::LINE_AA);
  text(image, "seconds from the first frame", {480, 705}, 0.45);
  if (!cv::imwrite(path, image)) throw Error(path + ": cannot write the plot");
}

}  // namespace lumistage
