// Qualisys Track Manager calibrations (.qca.txt), as Pose2Sim's demos ship them.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <optional>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/names.h"
#include "core/geometry/rig_import.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// One XML element's start tag: its name, attributes and line.
struct Tag {
  std::string name;
  std::map<std::string, std::string> attributes;
  int line = 0;
  bool closing = false;  // </name>
};

// The start and end tags of a small XML file in order (no entities, no CDATA: what QTM writes).
// Throws Error at a tag or attribute it cannot read.
std::vector<Tag> readTags(const std::string& text, const std::string& source) {
  std::vector<Tag> tags;
  int line = 1;
  size_t i = 0;
  const auto fail = [&](const std::string& what) {
    throw Error(fmt::format("{}:{}: {}", source, line, what));
  };
  while (i < text.size()) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<') {
      ++i;
      continue;
    }
    if (text.compare(i, 4, "<!--") == 0) {
      const size_t end = text.find("-->", i);
      if (end == std::string::npos) fail("a comment that never ends");
      line += int(std::count(text.begin() + long(i), text.begin() + long(end), '\n'));
      i = end + 3;
      continue;
    }
    if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "<!") == 0) {
      const size_t end = text.find('>', i);
      if (end == std::string::npos) fail("a declaration that never ends");
      line += int(std::count(text.begin() + long(i), text.begin() + long(end), '\n'));
      i = end + 1;
      continue;
    }
    Tag tag;
    tag.line = line;
    ++i;
    if (i < text.size() && text[i] == '/') tag.closing = true, ++i;
    while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) ||
                               text[i] == '_' || text[i] == '-' || text[i] == ':'))
      tag.name += text[i++];
    if (tag.name.empty()) fail("expected a tag name after '<'");
    while (true) {
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i])))
        line += text[i++] == '\n';
      if (i >= text.size()) fail("tag <" + tag.name + "> never ends");
      if (text[i] == '>') {
        ++i;
        break;
      }
      if (text.compare(i, 2, "/>") == 0) {
        i += 2;
        break;
      }
      std::string key;
      while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) ||
                                 text[i] == '_' || text[i] == '-' || text[i] == ':'))
        key += text[i++];
      if (key.empty() || i + 1 >= text.size() || text[i] != '=' ||
          (text[i + 1] != '"' && text[i + 1] != '\''))
        fail(fmt::format("<{}>: expected an attribute name=\"value\"", tag.name));
      const char quote = text[i + 1];
      const size_t end = text.find(quote, i + 2);
      if (end == std::string::npos)
        fail(fmt::format("<{}>: {}: the value never ends", tag.name, key));
      tag.attributes[key] = text.substr(i + 2, end - i - 2);
      line += int(std::count(text.begin() + long(i), text.begin() + long(end), '\n'));
      i = end + 1;
    }
    tags.push_back(std::move(tag));
  }
  return tags;
}

// Where a camera's attributes come from: the file and the camera's name.
struct Place {
  const std::string& source;
  const std::string& camera;
};

// Attribute `key` of `tag` as a number.
double number(const Tag& tag, const char* key, const Place& where) {
  const std::string at = fmt::format("{}:{}: camera '{}'", where.source, tag.line, where.camera);
  const auto it = tag.attributes.find(key);
  if (it == tag.attributes.end())
    throw Error(fmt::format("{}: {}: <{}> has no '{}'", at, key, tag.name, key));
  double value = 0;
  const std::string& text = it->second;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
    throw Error(fmt::format("{}: {}: expected a number, got {}", at, key, quotedInput(text)));
  return value;
}

}  // namespace

RigImport importQualisysRig(const fs::path& file, const RigImportOptions& options) {
  const std::string source = file.string();
  const std::vector<Tag> tags = readTags(readFile(file), source);
  RigImport result;
  std::vector<std::pair<std::string, Camera>> cameras;
  for (size_t t = 0; t < tags.size(); ++t) {
    if (tags[t].closing || tags[t].name != "camera") continue;
    const Tag& camera = tags[t];
    const auto serial = camera.attributes.find("serial");
    const std::string name = serial != camera.attributes.end() && !serial->second.empty()
                                 ? serial->second
                                 : fmt::format("cam{:02}", cameras.size() + 1);
    const Place where{source, name};
    const Tag *fov = nullptr, *transform = nullptr, *intrinsic = nullptr;
    size_t k = t + 1;
    for (; k < tags.size() && !(tags[k].closing && tags[k].name == "camera"); ++k) {
      if (tags[k].closing) continue;
      if (tags[k].name == "camera")
        throw Error(fmt::format("{}:{}: <camera> inside camera '{}'", source, tags[k].line, name));
      if (tags[k].name == "fov_video") fov = &tags[k];
      if (tags[k].name == "transform") transform = &tags[k];
      if (tags[k].name == "intrinsic") intrinsic = &tags[k];
    }
    if (k == tags.size())
      throw Error(
          fmt::format("{}:{}: camera '{}' never ends (</camera>)", source, camera.line, name));
    t = k;
    const auto active = camera.attributes.find("active");
    if (active != camera.attributes.end() && active->second == "0") {
      result.notes.push_back(
          fmt::format("camera '{}' is not active in the calibration: left out", name));
      continue;
    }
    if (!intrinsic || !transform) {
      // A marker camera (no video): Pose2Sim leaves them out too.
      result.notes.push_back(fmt::format("camera '{}' has no {}: left out", name,
                                         !intrinsic ? "<intrinsic>" : "<transform>"));
      continue;
    }
    if (!fov)
      throw Error(fmt::format("{}:{}: camera '{}' has no <fov_video> (its image size)", source,
                              camera.line, name));
    const double left = number(*fov, "left", where), right = number(*fov, "right", where),
                 top = number(*fov, "top", where), bottom = number(*fov, "bottom", where);
    // Inclusive pixel bounds: 0 .. 1087 is 1088 pixels.
    const int width = int(std::lround(right - left + 1)),
              height = int(std::lround(bottom - top + 1));
    if (width < 16 || height < 16 || width > 16384 || height > 16384)
      throw Error(fmt::format("{}:{}: fov_video: an image of {}x{} pixels", source, fov->line,
                              width, height));
    // Intrinsics in 1/64 pixel of the sensor, whose field of view starts at (left, top).
    Intrinsics k_;
    k_.fx = number(*intrinsic, "focalLengthU", where) / 64;
    k_.fy = number(*intrinsic, "focalLengthV", where) / 64;
    k_.cx = number(*intrinsic, "centerPointU", where) / 64 - left;
    k_.cy = number(*intrinsic, "centerPointV", where) / 64 - top;
    k_.skew = intrinsic->attributes.count("skew") ? number(*intrinsic, "skew", where) / 64 : 0.0;
    if (!(k_.fx > 0 && k_.fy > 0))
      throw Error(fmt::format("{}:{}: focalLengthU, focalLengthV: expected positive focal lengths",
                              source, intrinsic->line));
    // The distortion in the same 1/64 scale, as Pose2Sim reads and writes it.
    Distortion d;
    d.k1 = number(*intrinsic, "radialDistortion1", where) / 64;
    d.k2 = number(*intrinsic, "radialDistortion2", where) / 64;
    d.k3 = intrinsic->attributes.count("radialDistortion3")
               ? number(*intrinsic, "radialDistortion3", where) / 64
               : 0.0;
    d.p1 = number(*intrinsic, "tangentalDistortion1", where) / 64;
    d.p2 = number(*intrinsic, "tangentalDistortion2", where) / 64;
    // The pose: the camera's position in millimetres, and a rotation whose rows, turned half a
    // turn about the camera's x (QTM's camera looks down its -z with y up; ours down +z, y down),
    // are the world-to-camera rotation.
    Eigen::Matrix3d m;
    const char* keys[3][3] = {{"r11", "r12", "r13"}, {"r21", "r22", "r23"}, {"r31", "r32", "r33"}};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(r, c) = number(*transform, keys[r][c], where);
    if ((m * m.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
        m.determinant() < 0)
      throw Error(
          fmt::format("{}:{}: transform: r11..r33 are not a rotation", source, transform->line));
    const Eigen::Vector3d centre(number(*transform, "x", where) / 1000,
                                 number(*transform, "y", where) / 1000,
                                 number(*transform, "z", where) / 1000);
    const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
    // Re-orthonormalised: the file's nine numbers carry a few digits of noise.
    const Eigen::Matrix3d R = Eigen::Quaterniond(flip * m).normalized().toRotationMatrix();
    cameras.emplace_back(name, Camera(name, width, height, k_, d, R, -R * centre));
  }
  std::stable_sort(cameras.begin(), cameras.end(),
                   [](const auto& a, const auto& b) { return naturalLess(a.first, b.first); });
  std::vector<Camera> ordered;
  for (auto& [name, camera] : cameras) ordered.push_back(std::move(camera));
  if (ordered.empty()) throw Error(source + ": no video camera with an intrinsic and a transform");
  result.rig = assembleImportedRig(std::move(ordered), options, source);
  return result;
}

}  // namespace lumistage
