// Pose2Sim's and anipose's calibrations (Calib*.toml, OpenCV conventions), read with toml11.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string_view>
#include <toml.hpp>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/names.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/rotation.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// The numbers of a TOML array (integers or floats). Throws Error naming the table and key.
std::vector<double> numbers(const toml::value& array, const std::string& where) {
  if (!array.is_array()) throw Error(where + ": expected an array of numbers");
  std::vector<double> out;
  for (const toml::value& v : array.as_array()) {
    if (v.is_floating()) {
      out.push_back(v.as_floating());
    } else if (v.is_integer()) {
      out.push_back(double(v.as_integer()));
    } else {
      throw Error(where + ": expected numbers, found " + toml::format(v));
    }
    if (!std::isfinite(out.back())) throw Error(where + ": a number that is not finite");
  }
  return out;
}

const toml::value& key(const toml::value& table, const char* name, const std::string& where) {
  if (!table.contains(name)) throw Error(fmt::format("{}: no '{}'", where, name));
  return table.at(name);
}

Camera readCamera(const std::string& section, const toml::value& t, const std::string& source) {
  const std::string where = fmt::format("{}: [{}]", source, section);
  std::string name = section;
  if (t.contains("name")) {
    if (!t.at("name").is_string()) throw Error(where + ": name: expected a string");
    name = t.at("name").as_string();
  }
  if (t.contains("fisheye") && t.at("fisheye").is_boolean() && t.at("fisheye").as_boolean())
    throw Error(where + ": fisheye = true: the fisheye lens model is not supported");
  const std::vector<double> size = numbers(key(t, "size", where), where + ": size");
  if (size.size() != 2 || !(size[0] >= 16 && size[1] >= 16 && size[0] <= 16384 && size[1] <= 16384))
    throw Error(where + ": size: expected [width, height] in pixels");
  const toml::value& matrix = key(t, "matrix", where);
  if (!matrix.is_array() || matrix.as_array().size() != 3)
    throw Error(where + ": matrix: expected 3 rows of 3 numbers");
  Eigen::Matrix3d K;
  for (int r = 0; r < 3; ++r) {
    const std::vector<double> row =
        numbers(matrix.as_array()[size_t(r)], fmt::format("{}: matrix row {}", where, r + 1));
    if (row.size() != 3) throw Error(where + ": matrix: expected 3 rows of 3 numbers");
    for (int c = 0; c < 3; ++c) K(r, c) = row[size_t(c)];
  }
  if (!(K(0, 0) > 0 && K(1, 1) > 0) || K(2, 2) == 0)
    throw Error(where + ": matrix: expected positive focal lengths and K33 = 1");
  const std::vector<double> d = numbers(key(t, "distortions", where), where + ": distortions");
  if (d.size() < 4 || d.size() > 5) throw Error(where + ": distortions: expected k1 k2 p1 p2 [k3]");
  const std::vector<double> rvec = numbers(key(t, "rotation", where), where + ": rotation");
  const std::vector<double> tvec = numbers(key(t, "translation", where), where + ": translation");
  if (rvec.size() != 3) throw Error(where + ": rotation: expected a Rodrigues vector of 3");
  if (tvec.size() != 3) throw Error(where + ": translation: expected 3 numbers (metres)");
  const Eigen::Matrix3d R = rotationFromVector({rvec[0], rvec[1], rvec[2]});
  const Distortion distortion{d[0], d[1], d[2], d[3], d.size() > 4 ? d[4] : 0.0};
  return Camera(name, int(std::lround(size[0])), int(std::lround(size[1])),
                Intrinsics::fromMatrix(K), distortion, R,
                Eigen::Vector3d(tvec[0], tvec[1], tvec[2]));
}

// toml11's error as file:line: what (its first line, without toml11's "[error] toml::parse_x:"
// prefix); its own message draws the line's text below, which a log does not want.
std::string tomlError(const std::string& source, const toml::exception& e) {
  std::string what = e.what();
  what = what.substr(0, what.find('\n'));
  for (const char* prefix : {"[error] ", "toml::"}) {
    if (what.rfind(prefix, 0) == 0) what.erase(0, std::string(prefix).size());
  }
  const size_t colon = what.find(": ");
  if (colon != std::string::npos && what.find(' ') > colon) what.erase(0, colon + 2);
  return fmt::format("{}:{}: {}", source, e.location().line(), what);
}

// toml11 parses arrays and inline tables within each other by recursion, with no limit: a file
// nesting them 100,000 deep overflowed the stack. Their depth is measured first (outside strings
// and comments), and a file deeper than a calibration's few levels refused.
// TOML documents are UTF-8. toml11 reads a character's bytes by its first one without looking
// where the text ends: a quote, a lone 0xee and a quote read past its buffer (found by
// file_reader_fuzz). Text that is not UTF-8 is refused, naming its line, before toml11 sees it.
void checkTomlUtf8(std::string_view text, const std::string& source) {
  int line = 1;
  for (size_t i = 0; i < text.size();) {
    const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
    const unsigned char lead = byte(i);
    const size_t length = lead < 0x80                    ? 1
                          : lead >= 0xc2 && lead <= 0xdf ? 2
                          : lead >= 0xe0 && lead <= 0xef ? 3
                          : lead >= 0xf0 && lead <= 0xf4 ? 4
                                                         : 0;
    bool valid = length > 0 && i + length <= text.size();
    for (size_t k = 1; valid && k < length; ++k) valid = (byte(i + k) & 0xc0) == 0x80;
    if (!valid) {
      throw Error(
          fmt::format("{}:{}: byte {:#04x} is not UTF-8 text, which TOML is: refused "
                      "before reading it",
                      source, line, lead));
    }
    line += lead == '\n';
    i += length;
  }
}

void checkTomlNesting(std::string_view text, const std::string& source) {
  constexpr int kMaxDepth = 64;
  int depth = 0, line = 1;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '#') {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
    } else if (c == '"' || c == '\'') {
      // Strings: basic ones take backslash escapes; """ and ''' ones span lines.
      const bool multiline = text.compare(i, 3, std::string(3, c)) == 0;
      i += multiline ? 3 : 1;
      while (i < text.size()) {
        if (c == '"' && text[i] == '\\') {
          i += 2;
          continue;
        }
        if (text[i] == '\n') {
          if (!multiline) break;  // an unclosed string: toml11 says so
          ++line;
        }
        if (multiline ? text.compare(i, 3, std::string(3, c)) == 0 : text[i] == c) {
          i += multiline ? 2 : 0;
          break;
        }
        ++i;
      }
      if (i < text.size() && text[i] == '\n') --i;  // counted by the loop
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxDepth) {
        throw Error(
            fmt::format("{}:{}: arrays and tables nested deeper than {} levels: refused "
                        "before reading it",
                        source, line, kMaxDepth));
      }
    } else if (c == ']' || c == '}') {
      depth = std::max(0, depth - 1);
    }
  }
}

}  // namespace

RigImport importTomlRig(const fs::path& file, const RigImportOptions& options) {
  const std::string source = file.string();
  const std::string text = readFile(file);  // (a FIFO or a device refused, not read)
  checkTomlUtf8(text, source);
  checkTomlNesting(text, source);
  toml::value data;
  try {
    std::istringstream in(text);
    data = toml::parse(in, source);
  } catch (const toml::exception& e) {
    throw Error(tomlError(source, e));
  } catch (const std::exception& e) {
    throw Error(source + ": " + e.what());  // cannot open it
  }
  if (!data.is_table()) throw Error(source + ": expected TOML tables, one a camera");
  std::vector<std::string> sections;
  for (const auto& [section, value] : data.as_table())
    if (value.is_table() && section != "metadata") sections.push_back(section);
  // toml11 keeps a table's keys unordered: the cameras in their sections' natural order.
  std::sort(sections.begin(), sections.end(),
            [](const std::string& a, const std::string& b) { return naturalLess(a, b); });
  RigImport result;
  std::vector<Camera> cameras;
  try {
    for (const std::string& section : sections)
      cameras.push_back(readCamera(section, data.at(section), source));
  } catch (const toml::exception& e) {
    throw Error(tomlError(source, e));
  }
  if (cameras.empty()) throw Error(source + ": no camera tables ([cam_1] ...)");
  result.rig = assembleImportedRig(std::move(cameras), options, source);
  return result;
}

}  // namespace lumistage
