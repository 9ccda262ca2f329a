#include "core/geometry/rig_file.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/yaml_reader.h"

namespace lumistage {

namespace {

constexpr const char* kFormat = "lumistage-rig";
constexpr int kVersion = 1;

struct ParsedNode {
  RigNode node;
  std::vector<std::pair<std::string, YAML::Node>> camera_names;  // with their YAML, for messages
};

Camera parseCamera(const YamlReader& in, const YAML::Node& map, const std::string& key) {
  in.requireMap(map, key);
  in.checkKeys(map, key,
               {"name", "image_size", "intrinsics", "distortion", "rotation", "translation"});
  const std::string name =
      in.string(in.required(map, key, "name", "the camera's name"), YamlReader::child(key, "name"));

  const std::string size_key = YamlReader::child(key, "image_size");
  const YAML::Node size = in.required(map, key, "image_size", "[width, height] in pixels");
  in.requireSequence(size, size_key, 2);
  const int width = in.integer(size[0], YamlReader::item(size_key, 0));
  const int height = in.integer(size[1], YamlReader::item(size_key, 1));
  if (width <= 0 || height <= 0) {
    in.fail(size, size_key,
            fmt::format("expected a positive width and height, got {}x{}", width, height));
  }

  const std::string k_key = YamlReader::child(key, "intrinsics");
  const YAML::Node k = in.required(map, key, "intrinsics", "a map with fx, fy, cx, cy, skew");
  in.requireMap(k, k_key);
  in.checkKeys(k, k_key, {"fx", "fy", "cx", "cy", "skew"});
  auto k_number = [&](const char* name, const char* expected) {
    return in.number(in.required(k, k_key, name, expected), YamlReader::child(k_key, name));
  };
  Intrinsics intrinsics;
  intrinsics.fx = k_number("fx", "the horizontal focal length in pixels");
  intrinsics.fy = k_number("fy", "the vertical focal length in pixels");
  intrinsics.cx = k_number("cx", "the principal point's x in pixels");
  intrinsics.cy = k_number("cy", "the principal point's y in pixels");
  if (k["skew"]) intrinsics.skew = in.number(k["skew"], YamlReader::child(k_key, "skew"));
  for (const auto& [value, field] : {std::pair{intrinsics.fx, "fx"}, {intrinsics.fy, "fy"}}) {
    if (value <= 0) {
      in.fail(k[field], YamlReader::child(k_key, field),
              fmt::format("expected a positive focal length in pixels, got {}", value));
    }
  }

  Distortion distortion;
  if (const YAML::Node d = map["distortion"]) {
    const std::string d_key = YamlReader::child(key, "distortion");
    in.requireMap(d, d_key);
    in.checkKeys(d, d_key, {"k1", "k2", "p1", "p2", "k3"});
    auto d_number = [&](const char* name) {
      return in.number(in.required(d, d_key, name, "a coefficient of OpenCV's lens model"),
                       YamlReader::child(d_key, name));
    };
    distortion = {d_number("k1"), d_number("k2"), d_number("p1"), d_number("p2"), d_number("k3")};
  }

  const std::string r_key = YamlReader::child(key, "rotation");
  const YAML::Node r = in.required(map, key, "rotation", "a 3x3 world-to-camera rotation");
  in.requireSequence(r, r_key, 3);
  Eigen::Matrix3d R;
  for (int row = 0; row < 3; ++row) {
    const std::string row_key = YamlReader::item(r_key, row);
    in.requireSequence(r[row], row_key, 3);
    for (int col = 0; col < 3; ++col) {
      R(row, col) = in.number(r[row][col], YamlReader::item(row_key, col));
    }
  }
  const double orthonormality = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if (orthonormality > 1e-6) {
    in.fail(r, r_key,
            fmt::format("expected a rotation matrix (orthonormal rows), got one with "
                        "|R^T R - I| = {:.3g}{}",
                        orthonormality, std::abs(R.determinant()) < 1e-9 ? " (singular)" : ""));
  }
  if (R.determinant() < 0) {
    in.fail(r, r_key,
            "expected a rotation matrix, got a reflection (determinant -1): a left-handed frame?");
  }

  const std::string t_key = YamlReader::child(key, "translation");
  const YAML::Node t = in.required(map, key, "translation", "[tx, ty, tz] in metres");
  in.requireSequence(t, t_key, 3);
  const Eigen::Vector3d translation(in.number(t[0], YamlReader::item(t_key, 0)),
                                    in.number(t[1], YamlReader::item(t_key, 1)),
                                    in.number(t[2], YamlReader::item(t_key, 2)));
  try {
    return Camera(name, width, height, intrinsics, distortion, R, translation);
  } catch (const std::invalid_argument& e) {
    in.fail(map, key, e.what());
  }
}

// `stage: {lower: [x, y, z], upper: [x, y, z]}`, metres.
StageBox parseStage(const YamlReader& in, const YAML::Node& map) {
  const std::string key = "stage";
  in.requireMap(map, key);
  in.checkKeys(map, key, {"lower", "upper"});
  StageBox box;
  for (const char* corner : {"lower", "upper"}) {
    const std::string c_key = YamlReader::child(key, corner);
    const YAML::Node v = in.required(map, key, corner, "[x, y, z] in metres");
    in.requireSequence(v, c_key, 3);
    Eigen::Vector3d& p = std::string_view(corner) == "lower" ? box.lower : box.upper;
    for (int k = 0; k < 3; ++k) p[k] = in.number(v[k], YamlReader::item(c_key, k));
  }
  return box;
}

}  // namespace

Rig parseRig(std::string_view yaml_text, std::string_view source_name) {
  const YamlReader in{std::string(source_name)};
  const YAML::Node root = in.parseDocument(yaml_text);
  in.requireMap(root, "");
  // The format first: another kind of file's keys are not for the message.
  const YAML::Node format = in.required(root, "", "format", std::string("'") + kFormat + "'");
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    in.fail(format, "format",
            fmt::format("expected '{}', got {}: not a Lumistage rig file", kFormat,
                        format.IsScalar() ? quotedInput(format.Scalar()) : "no text"));
  }
  in.checkKeys(root, "", {"format", "version", "stage", "nodes", "cameras"});
  const YAML::Node version = in.required(root, "", "version", "1");
  const int v = in.integer(version, "version");
  if (v != kVersion) {
    in.fail(version, "version",
            fmt::format("this Lumistage reads rig files of version {}, the file has version {}{}",
                        kVersion, v, v > kVersion ? " (written by a newer Lumistage)" : ""));
  }

  const YAML::Node cameras_yaml = in.required(root, "", "cameras", "a list of cameras");
  in.requireSequence(cameras_yaml, "cameras");
  if (cameras_yaml.size() == 0) in.fail(cameras_yaml, "cameras", "expected at least one camera");
  std::vector<Camera> cameras;
  for (size_t i = 0; i < cameras_yaml.size(); ++i) {
    const std::string key = YamlReader::item("cameras", i);
    cameras.push_back(parseCamera(in, cameras_yaml[i], key));
    for (size_t j = 0; j + 1 < cameras.size(); ++j) {
      if (cameras[j].name() == cameras.back().name()) {
        in.fail(cameras_yaml[i]["name"], YamlReader::child(key, "name"),
                fmt::format("camera '{}' is already defined as cameras[{}]; names must be unique",
                            cameras.back().name(), j));
      }
    }
  }

  const YAML::Node nodes_yaml = in.required(root, "", "nodes", "a list of camera nodes");
  in.requireSequence(nodes_yaml, "nodes");
  std::vector<RigNode> nodes;
  std::vector<std::string> owner(cameras.size());
  for (size_t i = 0; i < nodes_yaml.size(); ++i) {
    const std::string key = YamlReader::item("nodes", i);
    const YAML::Node n = nodes_yaml[i];
    in.requireMap(n, key);
    in.checkKeys(n, key, {"name", "host", "cameras"});
    RigNode node;
    node.name =
        in.string(in.required(n, key, "name", "the node's name"), YamlReader::child(key, "name"));
    if (!isValidName(node.name)) {
      in.fail(n["name"], YamlReader::child(key, "name"),
              "invalid node name '" + node.name +
                  "': expected 1-64 characters of A-Z a-z 0-9 _ . - (not starting with . or -)");
    }
    for (const RigNode& other : nodes) {
      if (other.name == node.name) {
        in.fail(n["name"], YamlReader::child(key, "name"),
                "node '" + node.name + "' is defined twice; names must be unique");
      }
    }
    if (n["host"]) {
      // A host name or address (what the rig file is written back with, quoted).
      node.host = in.string(n["host"], YamlReader::child(key, "host"));
      const bool valid = !node.host.empty() && node.host.size() <= 253 &&
                         std::all_of(node.host.begin(), node.host.end(), [](char c) {
                           return std::isalnum(static_cast<unsigned char>(c)) || c == '.' ||
                                  c == '-' || c == ':' || c == '_';
                         });
      if (!valid) {
        in.fail(n["host"], YamlReader::child(key, "host"),
                "expected a host name or address (letters, digits, '.', '-', ':', '_'), got '" +
                    node.host + "'");
      }
    }
    const std::string c_key = YamlReader::child(key, "cameras");
    const YAML::Node list = in.required(n, key, "cameras", "a list of camera names");
    in.requireSequence(list, c_key);
    for (size_t j = 0; j < list.size(); ++j) {
      const std::string camera = in.string(list[j], YamlReader::item(c_key, j));
      int index = -1;
      for (size_t c = 0; c < cameras.size(); ++c) {
        if (cameras[c].name() == camera) index = static_cast<int>(c);
      }
      if (index < 0) {
        in.fail(list[j], YamlReader::item(c_key, j),
                "node '" + node.name + "' refers to unknown camera '" + camera +
                    "'; expected one of the names under 'cameras'");
      }
      if (!owner[index].empty()) {
        in.fail(list[j], YamlReader::item(c_key, j),
                "camera '" + camera + "' is already owned by node '" + owner[index] +
                    "'; a camera belongs to exactly one node");
      }
      owner[index] = node.name;
      node.cameras.push_back(index);
    }
    nodes.push_back(std::move(node));
  }
  for (size_t c = 0; c < cameras.size(); ++c) {
    if (owner[c].empty()) {
      in.fail(nodes_yaml, "nodes",
              "camera '" + cameras[c].name() + "' belongs to no node; list it under one node");
    }
  }
  Rig rig(std::move(cameras), std::move(nodes));
  if (const YAML::Node stage = root["stage"]) {
    try {
      rig.setStage(parseStage(in, stage));
    } catch (const std::invalid_argument& e) {
      in.fail(stage, "stage", e.what());
    }
  }
  return rig;
}

Rig loadRig(const std::filesystem::path& path) {
  return parseRig(readFile(path), path.string());
}

// -0.0 is written as 0: the same value, without a sign that reads as a mistake.
static double tidy(double x) {
  return x + 0.0;
}

std::string formatRig(const Rig& rig) {
  // Written by hand rather than by an emitter: a rig file is read and edited by people, so it
  // gets a header, one line per matrix row, and shortest round-trip numbers ("{}" in fmt).
  std::string out;
  out += "# Lumistage rig file: see docs/rig-file.md.\n";
  out += "# World frame: metres, z up, stage floor at z = 0. Camera frame: x right, y down, z\n";
  out += "# forward; x_cam = rotation * x_world + translation. Pixel (0,0): centre of top-left.\n";
  out += fmt::format("format: {}\nversion: {}\n", kFormat, kVersion);
  if (const std::optional<StageBox>& stage = rig.stage()) {
    out += "stage:  # the capture volume the tracker searches, metres\n";
    out += fmt::format("  lower: [{}, {}, {}]\n", tidy(stage->lower.x()), tidy(stage->lower.y()),
                       tidy(stage->lower.z()));
    out += fmt::format("  upper: [{}, {}, {}]\n", tidy(stage->upper.x()), tidy(stage->upper.y()),
                       tidy(stage->upper.z()));
  }
  out += "nodes:\n";
  for (const RigNode& node : rig.nodes()) {
    out += fmt::format("  - name: {}\n", node.name);
    if (!node.host.empty()) out += fmt::format("    host: \"{}\"\n", node.host);
    out += "    cameras: [";
    for (size_t i = 0; i < node.cameras.size(); ++i) {
      out += (i ? ", " : "") + rig.camera(node.cameras[i]).name();
    }
    out += "]\n";
  }
  out += "cameras:\n";
  for (const Camera& c : rig.cameras()) {
    const Intrinsics& k = c.intrinsics();
    const Distortion& d = c.distortion();
    const Eigen::Matrix3d& R = c.rotation();
    const Eigen::Vector3d& t = c.translation();
    out += fmt::format("  - name: {}\n", c.name());
    out += fmt::format("    image_size: [{}, {}]\n", c.width(), c.height());
    out += fmt::format("    intrinsics: {{fx: {}, fy: {}, cx: {}, cy: {}, skew: {}}}\n", tidy(k.fx),
                       tidy(k.fy), tidy(k.cx), tidy(k.cy), tidy(k.skew));
    out += fmt::format("    distortion: {{k1: {}, k2: {}, p1: {}, p2: {}, k3: {}}}\n", tidy(d.k1),
                       tidy(d.k2), tidy(d.p1), tidy(d.p2), tidy(d.k3));
    out += "    rotation:\n";
    for (int row = 0; row < 3; ++row) {
      out +=
          fmt::format("      - [{}, {}, {}]\n", tidy(R(row, 0)), tidy(R(row, 1)), tidy(R(row, 2)));
    }
    out += fmt::format("    translation: [{}, {}, {}]\n", tidy(t.x()), tidy(t.y()), tidy(t.z()));
  }
  return out;
}

void saveRig(const Rig& rig, const std::filesystem::path& path) {
  writeFileAtomically(path, formatRig(rig));
}

}  // namespace lumistage
