#include "core/body/mesh_axes.h"

#include <assimp/commonMetaData.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <cctype>
#include <cmath>
#include <numbers>
#include <string_view>

#include "core/base/error.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// A file's frame in the scene's coordinates: the unit axes along which the actor's left, front
// and up lie, and the length of the file's unit in metres.
struct FileFrame {
  Eigen::Vector3f left, front, up;
  float metres = 1;
};

// Assimp's convention (and glTF's): +Y up, the actor facing +Z, so +X is the actor's left.
FileFrame assimpConvention() {
  return {Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitY(), 1};
}

// Ours: the actor's left is -x, its front +y, up +z. The frame's axes are orthonormal, so the map
// is `metres` times (ours) * (file axes)^T.
Eigen::Matrix3f toOurs(const FileFrame& f) {
  Eigen::Matrix3f file;
  file.col(0) = f.left;
  file.col(1) = f.front;
  file.col(2) = f.up;
  const Eigen::Matrix3f ours = Eigen::Vector3f(-1, 1, 1).asDiagonal();
  return f.metres * ours * file.transpose();
}

// "+Y", "-Z": the coordinate axis nearest to v.
std::string axisName(const Eigen::Vector3f& v) {
  Eigen::Index i = 0;
  v.cwiseAbs().maxCoeff(&i);
  return std::string(v[i] < 0 ? "-" : "+") + "XYZ"[i];
}

// The coordinate axis within 35 degrees of d, if one is.
std::optional<Eigen::Vector3f> snapped(const Eigen::Vector3f& d) {
  const float n = d.norm();
  if (!std::isfinite(n) || n <= 0) return std::nullopt;
  Eigen::Index i = 0;
  const float largest = d.cwiseAbs().maxCoeff(&i);
  if (largest < std::cos(35 * std::numbers::pi_v<float> / 180) * n) return std::nullopt;
  Eigen::Vector3f axis = Eigen::Vector3f::Zero();
  axis[i] = d[i] < 0 ? -1 : 1;
  return axis;
}

// A joint name's words, lower case: split at what is not a letter or digit and where case
// changes ("mixamorig:LeftUpLeg" -> mixamorig, left, up, leg; "LFoot" -> l, foot).
std::vector<std::string> words(std::string_view name) {
  std::vector<std::string> out;
  std::string word;
  const auto upper = [](char c) { return std::isupper(static_cast<unsigned char>(c)) != 0; };
  const auto lower = [](char c) { return std::islower(static_cast<unsigned char>(c)) != 0; };
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (!std::isalnum(static_cast<unsigned char>(c))) {
      if (!word.empty()) out.push_back(std::move(word));
      word.clear();
      continue;
    }
    const bool boundary =
        i > 0 && upper(c) &&
        (lower(name[i - 1]) || (upper(name[i - 1]) && i + 1 < name.size() && lower(name[i + 1])));
    if (boundary && !word.empty()) {
      out.push_back(std::move(word));
      word.clear();
    }
    word += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (!word.empty()) out.push_back(std::move(word));
  return out;
}

bool holdsAny(const std::vector<std::string>& name_words,
              std::initializer_list<const char*> parts) {
  for (const std::string& w : name_words) {
    for (const char* part : parts) {
      if (w.find(part) != std::string::npos) return true;
    }
  }
  return false;
}

// +1 for a joint of the left side, -1 for the right, 0 for neither (or both).
int sideOf(const std::vector<std::string>& name_words) {
  bool left = false, right = false;
  for (const std::string& w : name_words) {
    left = left || w == "l" || w.starts_with("left");
    right = right || w == "r" || w.starts_with("right");
  }
  return left == right ? 0 : left ? 1 : -1;
}

float metaNumber(const aiMetadata& meta, const std::string& key, float fallback) {
  double d = 0;
  if (meta.Get(key, d)) return static_cast<float>(d);
  float f = 0;
  if (meta.Get(key, f)) return f;
  int32_t i = 0;
  if (meta.Get(key, i)) return static_cast<float>(i);
  return fallback;
}

// The frame an FBX file's GlobalSettings declare (their defaults, Maya's, where one is missing).
FileFrame fbxFrame(const aiMetadata* meta, const fs::path& path) {
  const aiMetadata none;
  const aiMetadata& m = meta ? *meta : none;
  const auto axis = [&](const char* name, float fallback, const char* sign_name) {
    const float index = metaNumber(m, name, fallback);
    const float sign = metaNumber(m, sign_name, 1);
    if (!(index == 0 || index == 1 || index == 2) || !(sign == 1 || sign == -1)) {
      throw Error(
          fmt::format("{}: FBX GlobalSettings {} {} with {} {}: expected an axis 0, 1 or "
                      "2 and a sign 1 or -1",
                      path.string(), name, index, sign_name, sign));
    }
    Eigen::Vector3f v = Eigen::Vector3f::Zero();
    v[static_cast<int>(index)] = sign;
    return v;
  };
  FileFrame f;
  f.up = axis("UpAxis", 1, "UpAxisSign");
  f.front = axis("FrontAxis", 2, "FrontAxisSign");
  f.left = axis("CoordAxis", 0, "CoordAxisSign");
  if (std::abs(f.up.dot(f.front)) + std::abs(f.up.dot(f.left)) + std::abs(f.front.dot(f.left)) !=
      0) {
    throw Error(
        fmt::format("{}: FBX GlobalSettings put UpAxis ({}), FrontAxis ({}) and CoordAxis "
                    "({}) on the same axis: expected three different axes",
                    path.string(), axisName(f.up), axisName(f.front), axisName(f.left)));
  }
  const float centimetres = metaNumber(m, "UnitScaleFactor", 1);
  if (!std::isfinite(centimetres) || centimetres < 1e-6f || centimetres > 1e6f) {
    throw Error(
        fmt::format("{}: FBX GlobalSettings UnitScaleFactor {}: expected a positive number "
                    "of centimetres per unit (1 for centimetres, 100 for metres)",
                    path.string(), centimetres));
  }
  f.metres = centimetres / 100;
  return f;
}

bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

}  // namespace

SkeletonAxes skeletonAxes(const std::vector<std::string>& names,
                          const std::vector<Eigen::Vector3f>& positions) {
  Eigen::Vector3f head = Eigen::Vector3f::Zero(), neck = Eigen::Vector3f::Zero(),
                  feet = Eigen::Vector3f::Zero(), left = Eigen::Vector3f::Zero(),
                  right = Eigen::Vector3f::Zero();
  int heads = 0, necks = 0, feet_count = 0, lefts = 0, rights = 0;
  for (size_t j = 0; j < names.size() && j < positions.size(); ++j) {
    const std::vector<std::string> w = words(names[j]);
    const Eigen::Vector3f& p = positions[j];
    const auto add = [&](bool is, Eigen::Vector3f& sum, int& count) {
      if (!is) return;
      sum += p;
      ++count;
    };
    add(holdsAny(w, {"head"}), head, heads);
    add(holdsAny(w, {"neck"}), neck, necks);
    add(holdsAny(w, {"foot", "toe", "ankle", "heel"}), feet, feet_count);
    add(sideOf(w) > 0, left, lefts);
    add(sideOf(w) < 0, right, rights);
  }
  SkeletonAxes out;
  if (heads == 0) {  // no head joint: the neck will do
    head = neck;
    heads = necks;
  }
  if (heads == 0 || feet_count == 0) return out;
  out.up = snapped(head / heads - feet / feet_count);
  if (!out.up || lefts == 0 || rights == 0) return out;
  const Eigen::Vector3f across = left / lefts - right / rights;
  out.left = snapped(across - across.dot(*out.up) * *out.up);
  return out;
}

Eigen::Matrix3f sceneToOurs(const aiScene& scene, const fs::path& path,
                            const SkeletonAxes& skeleton) {
  std::string format = "unknown";
  aiString name;
  if (scene.mMetaData && scene.mMetaData->Get(std::string(AI_METADATA_SOURCE_FORMAT), name)) {
    format = name.C_Str();
  }
  const std::string file = path.string();
  FileFrame frame = assimpConvention();
  bool declared = true;
  std::string kind = format;  // for messages
  if (contains(format, "FBX")) {
    frame = fbxFrame(scene.mMetaData, path);
    kind = "FBX";
  } else if (contains(format, "glTF")) {
    kind = "glTF";
  } else if (contains(format, "Collada")) {
    kind = "COLLADA";
  } else if (format.starts_with("Assimp ")) {
    kind = "Assimp";
  } else {
    declared = false;
    if (contains(format, "XFile")) kind = "DirectX .X";
  }

  if (declared) {
    if (skeleton.up && skeleton.up->dot(frame.up) < 0.5f) {
      spdlog::warn(
          "{}: its skeleton stands along {} (head above feet) but the file says {} is "
          "up ({}): following the file, the body will not stand upright",
          file, axisName(*skeleton.up), axisName(frame.up), kind);
    }
    return toOurs(frame);
  }

  const bool xfile = kind == "DirectX .X";
  if (!skeleton.up) {
    spdlog::warn(
        "{}: {} gives no up axis of its own and no joints named head and foot show "
        "which way its skeleton stands: taking +Y as up{}",
        file, xfile ? "a DirectX .X file" : "its format (" + kind + ")",
        xfile ? " (DirectX's convention)" : "");
    return toOurs(frame);
  }
  FileFrame from_skeleton = frame;
  from_skeleton.up = *skeleton.up;
  if (skeleton.left) {
    from_skeleton.left = *skeleton.left;
  } else {
    // The convention turned the shortest way onto the skeleton's up axis.
    const Eigen::Vector3f turned =
        Eigen::Quaternionf::FromTwoVectors(frame.up, from_skeleton.up) * frame.left;
    from_skeleton.left = snapped(turned).value_or(frame.left);
  }
  from_skeleton.front = from_skeleton.left.cross(from_skeleton.up);
  const bool differs = from_skeleton.up != frame.up || from_skeleton.left != frame.left;
  if (differs || !xfile) {
    spdlog::warn(
        "{}: {}: standing it up by its skeleton (head above feet), {} up, the actor facing {}{}",
        file,
        xfile ? "a DirectX .X file is +Y up, the actor facing +Z, only by convention, and this "
                "one's skeleton stands otherwise"
              : "its format (" + kind + ") gives no axes of its own",
        axisName(from_skeleton.up), axisName(from_skeleton.front),
        skeleton.left ? "" : " (a guess: no joints named left and right)");
  }
  return toOurs(from_skeleton);
}

}  // namespace lumistage
