#include "core/calib/wand_session.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/geometry/camera.h"

namespace lumistage {

WandSession::WandSession(std::vector<WandCamera> cameras, int samples)
    : cameras_(std::move(cameras)) {
  addSamples(samples);
}

std::optional<int> WandSession::findCamera(std::string_view name) const {
  for (int c = 0; c < cameraCount(); ++c) {
    if (cameras_[c].name == name) return c;
  }
  return std::nullopt;
}

int WandSession::addSamples(int count) {
  const int first = samples_;
  samples_ += count;
  pixels_.resize(static_cast<size_t>(samples_) * cameras_.size(), Eigen::Vector2d::Zero());
  seen_.resize(pixels_.size(), 0);
  return first;
}

void WandSession::set(int sample, int camera, const Eigen::Vector2d& pixel) {
  pixels_[index(sample, camera)] = pixel;
  seen_[index(sample, camera)] = 1;
}

void WandSession::clear(int sample, int camera) {
  seen_[index(sample, camera)] = 0;
}

int WandSession::observationCount(int camera) const {
  int n = 0;
  for (int s = 0; s < samples_; ++s) n += has(s, camera);
  return n;
}

int WandSession::viewCount(int sample) const {
  int n = 0;
  for (int c = 0; c < cameraCount(); ++c) n += has(sample, c);
  return n;
}

namespace {

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

}  // namespace

WandSession parseWandSession(std::string_view text, std::string_view source_name) {
  std::vector<WandCamera> cameras;
  struct Point {
    int sample, camera;
    Eigen::Vector2d pixel;
  };
  std::vector<Point> points;
  std::vector<std::pair<int, int>> pairs;
  std::vector<FloorMark> marks;
  int max_sample = -1;
  int line_number = 0;
  bool header = false;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    auto fail = [&](const std::string& what) -> Error {
      return Error(locate(source_name, line_number, "", what));
    };
    const std::vector<std::string_view> w = splitWords(line);
    if (w.empty() || w[0][0] == '#') {
      constexpr std::string_view kHeader = "# lumistage wand points";
      if (line_number == 1 && line.rfind(kHeader, 0) == 0) {
        const std::vector<std::string_view> version = splitWords(line.substr(kHeader.size()));
        if (version.size() != 1 || version[0] != "1")
          throw fail(fmt::format("wand points version {}: this build reads version 1",
                                 quotedInput(line.substr(kHeader.size()))));
        header = true;
      }
      if (end == text.size()) break;
      continue;
    }
    if (!header) throw fail("expected the first line '# lumistage wand points 1'");
    auto integer = [&](std::string_view s, const char* what) {
      int v = 0;
      const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
      if (r.ec != std::errc() || r.ptr != s.data() + s.size() || v < 0)
        throw fail(
            fmt::format("{}: expected a non-negative integer, found {}", what, quotedInput(s)));
      return v;
    };
    // Samples are frames of a wand's wave: a million is over nine hours at 30 frames a second,
    // and every sample takes room for every camera.
    constexpr int kMaxSample = 1'000'000;
    auto sampleId = [&](std::string_view s) {
      const int v = integer(s, "sample");
      if (v >= kMaxSample)
        throw fail(fmt::format("sample {} is beyond the largest, {}", v, kMaxSample - 1));
      return v;
    };
    auto number = [&](std::string_view s, const char* what) {
      double v = 0;
      const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
      if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v))
        throw fail(fmt::format("{}: expected a number, found {}", what, quotedInput(s)));
      return v;
    };
    auto expect = [&](size_t n, const char* form) {
      if (w.size() != n) throw fail(fmt::format("expected '{}', found {} words", form, w.size()));
    };
    if (w[0] == "camera") {
      expect(4, "camera NAME WIDTH HEIGHT");
      WandCamera c{std::string(w[1]), integer(w[2], "width"), integer(w[3], "height")};
      if (!isValidName(c.name))
        throw fail(fmt::format("{} is not a valid camera name", quotedInput(c.name)));
      if (c.width <= 0 || c.height <= 0) throw fail("camera size must be positive");
      for (const WandCamera& o : cameras) {
        if (o.name == c.name) throw fail(fmt::format("camera '{}' listed twice", c.name));
      }
      if (!points.empty()) throw fail("camera lines must come before point lines");
      cameras.push_back(c);
    } else if (w[0] == "point") {
      expect(5, "point SAMPLE CAMERA X_PX Y_PX");
      const int sample = sampleId(w[1]);
      int camera = -1;
      for (size_t c = 0; c < cameras.size(); ++c) {
        if (cameras[c].name == w[2]) camera = static_cast<int>(c);
      }
      if (camera < 0)
        throw fail(fmt::format("unknown camera {} (no camera line for it)", quotedInput(w[2])));
      const Eigen::Vector2d pixel(number(w[3], "x_px"), number(w[4], "y_px"));
      const WandCamera& c = cameras[camera];
      // Beyond the image by less than a pixel (a centroid of a blob cut by the image's edge):
      // dropped with a warning. Further: not this camera's point.
      const double beyond = std::max({-0.5 - pixel.x(), -0.5 - pixel.y(),
                                      pixel.x() - (c.width - 0.5), pixel.y() - (c.height - 0.5)});
      if (beyond > 1.0)
        throw fail(fmt::format("pixel ({}, {}) is outside camera {}'s {}x{} image", pixel.x(),
                               pixel.y(), c.name, c.width, c.height));
      if (beyond >= 0) {
        spdlog::warn("{}", locate(source_name, line_number, "",
                                  fmt::format("pixel ({}, {}) lies just off camera {}'s {}x{} "
                                              "image: left out",
                                              pixel.x(), pixel.y(), c.name, c.width, c.height)));
      } else {
        points.push_back({sample, camera, pixel});
      }
      max_sample = std::max(max_sample, sample);
    } else if (w[0] == "pair") {
      expect(3, "pair SAMPLE_A SAMPLE_B");
      pairs.emplace_back(sampleId(w[1]), sampleId(w[2]));
      max_sample = std::max({max_sample, pairs.back().first, pairs.back().second});
    } else if (w[0] == "floor") {
      expect(5, "floor SAMPLE X_M Y_M Z_M");
      marks.push_back(
          {sampleId(w[1]), {number(w[2], "x_m"), number(w[3], "y_m"), number(w[4], "z_m")}});
      max_sample = std::max(max_sample, marks.back().sample);
    } else {
      throw fail(fmt::format("unknown line kind {} (expected camera, point, pair or floor)",
                             quotedInput(w[0])));
    }
    if (end == text.size()) break;
  }
  if (!header)
    throw Error(locate(source_name, 0, "", "empty file: expected '# lumistage wand points 1'"));
  if (cameras.empty()) throw Error(locate(source_name, 0, "", "no camera lines"));
  WandSession session(std::move(cameras), max_sample + 1);
  for (const Point& p : points) session.set(p.sample, p.camera, p.pixel);
  session.wand_pairs = std::move(pairs);
  session.floor_marks = std::move(marks);
  return session;
}

WandSession loadWandSession(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open the wand points file", path.string()));
  std::ostringstream text;
  text << in.rdbuf();
  return parseWandSession(text.str(), path.string());
}

std::string formatWandSession(const WandSession& session) {
  std::string out = "# lumistage wand points 1\n";
  for (const WandCamera& c : session.cameras()) {
    out += fmt::format("camera {} {} {}\n", c.name, c.width, c.height);
  }
  for (const auto& [a, b] : session.wand_pairs) out += fmt::format("pair {} {}\n", a, b);
  for (const FloorMark& m : session.floor_marks) {
    out +=
        fmt::format("floor {} {} {} {}\n", m.sample, m.world_m.x(), m.world_m.y(), m.world_m.z());
  }
  out += "# point SAMPLE CAMERA X_PX Y_PX\n";
  for (int s = 0; s < session.sampleCount(); ++s) {
    for (int c = 0; c < session.cameraCount(); ++c) {
      if (!session.has(s, c)) continue;
      const Eigen::Vector2d& p = session.pixel(s, c);
      out += fmt::format("point {} {} {:.4f} {:.4f}\n", s, session.cameras()[c].name, p.x(), p.y());
    }
  }
  return out;
}

void saveWandSession(const WandSession& session, const std::filesystem::path& path) {
  writeFileAtomically(path, formatWandSession(session));
}

}  // namespace lumistage
