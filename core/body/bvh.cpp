#include "core/body/bvh.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {

namespace {

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// Channel kinds: 0..2 position x/y/z, 3..5 rotation x/y/z.
struct BvhJoint {
  std::string name;
  int parent = -1;
  int line = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<int> channels;
  int first_value = 0;  // index of its first channel in a frame line
};

struct BvhFile {
  std::vector<BvhJoint> joints;
  std::vector<std::pair<int, Eigen::Vector3d>> end_sites;  // joint, OFFSET
  double frame_time_s = 0;
  int value_count = 0;
  std::vector<std::vector<double>> frames;
  std::vector<int> frame_lines;  // each frame's line in the file
};

struct Token {
  std::string_view text;
  int line;
};

class Parser {
 public:
  Parser(std::string file, std::string_view text) : file_(std::move(file)) {
    // Split into lines (CR LF tolerated), then hierarchy tokens until MOTION.
    size_t start = 0;
    while (start <= text.size()) {
      size_t end = text.find('\n', start);
      if (end == std::string_view::npos) end = text.size();
      std::string_view line = text.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      lines_.push_back(line);
      if (end == text.size()) break;
      start = end + 1;
    }
  }

  BvhFile parse() {
    BvhFile out;
    tokenizeHierarchy();
    expect("HIERARCHY");
    expect("ROOT");
    parseHierarchy(out);
    if (pos_ >= tokens_.size() || tokens_[pos_].text != "MOTION") {
      fail(pos_ < tokens_.size() ? tokens_[pos_].line : lastLine(),
           "expected MOTION after the hierarchy" + found());
    }
    parseMotion(out, tokens_[pos_].line);
    return out;
  }

 private:
  [[noreturn]] void fail(int line, const std::string& message) const {
    throw Error(locate(file_, line, "", message));
  }
  int lastLine() const { return static_cast<int>(lines_.size()); }
  std::string found() const {
    if (pos_ >= tokens_.size()) return ", found the end of the file (truncated?)";
    return ", found " + quotedInput(tokens_[pos_].text);
  }

  void tokenizeHierarchy() {
    for (size_t l = 0; l < lines_.size(); ++l) {
      std::string_view line = lines_[l];
      size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        size_t j = i;
        while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
        if (j > i) tokens_.push_back({line.substr(i, j - i), static_cast<int>(l) + 1});
        if (line.substr(i, j - i) == "MOTION") {
          return;
        }
        i = j;
      }
    }
  }

  const Token& next(const char* what) {
    if (pos_ >= tokens_.size()) fail(lastLine(), std::string("expected ") + what + found());
    return tokens_[pos_++];
  }
  void expect(std::string_view keyword) {
    if (pos_ >= tokens_.size() || tokens_[pos_].text != keyword) {
      fail(pos_ < tokens_.size() ? tokens_[pos_].line : lastLine(),
           fmt::format("expected '{}'{}", keyword, found()));
    }
    ++pos_;
  }
  double number(const Token& t, const char* what) const {
    double value = 0;
    const char* end = t.text.data() + t.text.size();
    auto [ptr, ec] = std::from_chars(t.text.data(), end, value);
    if (ec != std::errc() || ptr != end || !std::isfinite(value)) {
      fail(t.line, fmt::format("expected a number for {}, found {}", what, quotedInput(t.text)));
    }
    return value;
  }
  Eigen::Vector3d offset() {
    expect("OFFSET");
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) v[k] = number(next("an OFFSET value"), "OFFSET");
    return v;
  }

  // A joint's name, OFFSET and CHANNELS, up to its children: the joint is added to `out` and its
  // index returned. Its children and its '}' are for parseHierarchy.
  int parseJointHead(BvhFile& out, int parent) {
    const Token& name = next("a joint name");
    if (name.text == "{") fail(name.line, "expected a joint name before '{'");
    BvhJoint joint;
    joint.name = std::string(name.text);
    joint.parent = parent;
    joint.line = name.line;
    expect("{");
    joint.offset = offset();
    expect("CHANNELS");
    const Token& count_token = next("a channel count");
    const double count = number(count_token, "the channel count");
    if (count < 0 || count > 6 || count != std::floor(count)) {
      fail(count_token.line, fmt::format("expected a channel count from 0 to 6, found {}",
                                         quotedInput(count_token.text)));
    }
    static constexpr std::string_view kNames[] = {"Xposition", "Yposition", "Zposition",
                                                  "Xrotation", "Yrotation", "Zrotation"};
    for (int c = 0; c < static_cast<int>(count); ++c) {
      const Token& t = next("a channel name");
      const auto* it = std::find(std::begin(kNames), std::end(kNames), t.text);
      if (it == std::end(kNames)) {
        fail(t.line, fmt::format("unknown channel {} of joint {}, expected one of Xposition, "
                                 "Yposition, Zposition, Xrotation, Yrotation, Zrotation",
                                 quotedInput(t.text), quotedInput(joint.name)));
      }
      joint.channels.push_back(static_cast<int>(it - std::begin(kNames)));
    }
    joint.first_value = out.value_count;
    out.value_count += static_cast<int>(joint.channels.size());
    out.joints.push_back(std::move(joint));
    return static_cast<int>(out.joints.size()) - 1;
  }

  // The joints from the root on, depth first. The joints still open are a stack of our own, not
  // the call stack: a file of 50,000 nested joints is read like any other (it crashed the parser
  // when each level was a call).
  void parseHierarchy(BvhFile& out) {
    std::vector<int> open{parseJointHead(out, -1)};
    while (!open.empty()) {
      const int index = open.back();
      if (pos_ >= tokens_.size()) {
        fail(lastLine(), fmt::format("expected '}}' closing joint {} (line {}), found the end "
                                     "of the file (truncated?)",
                                     quotedInput(out.joints[index].name), out.joints[index].line));
      }
      const Token& t = tokens_[pos_];
      if (t.text == "}") {
        ++pos_;
        open.pop_back();
      } else if (t.text == "MOTION") {
        fail(t.line, fmt::format("expected '}}' closing joint {} (line {}) before MOTION",
                                 quotedInput(out.joints[index].name), out.joints[index].line));
      } else if (t.text == "JOINT") {
        ++pos_;
        open.push_back(parseJointHead(out, index));
      } else if (t.text == "End") {
        ++pos_;
        expect("Site");
        expect("{");
        out.end_sites.push_back({index, offset()});
        expect("}");
      } else {
        fail(t.line, fmt::format("expected JOINT, End Site or '}}' in joint {}, found {}",
                                 quotedInput(out.joints[index].name), quotedInput(t.text)));
      }
    }
  }

  // The motion section, line by line: a frame line must hold exactly one value per channel.
  void parseMotion(BvhFile& out, int motion_line) {
    size_t l = static_cast<size_t>(motion_line);  // index of the line after MOTION
    double announced = 0;                         // 'Frames:'
    int frames_line = 0;
    auto nextLine = [&](const char* what) -> std::pair<std::string_view, int> {
      while (l < lines_.size()) {
        std::string_view line = lines_[l++];
        if (line.find_first_not_of(" \t") != std::string_view::npos) {
          return {line, static_cast<int>(l)};
        }
      }
      fail(lastLine(),
           std::string("expected ") + what + ", found the end of the file (truncated?)");
    };
    auto split = [](std::string_view line) {
      std::vector<std::string_view> words;
      size_t i = 0;
      while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        size_t j = i;
        while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
        if (j > i) words.push_back(line.substr(i, j - i));
        i = j;
      }
      return words;
    };
    {
      auto [line, number_] = nextLine("'Frames: N'");
      auto words = split(line);
      if (words.size() != 2 || words[0] != "Frames:") {
        fail(number_, "expected 'Frames: N', found " + quotedInput(line));
      }
      const double n = number({words[1], number_}, "Frames");
      if (n < 0 || n != std::floor(n)) fail(number_, "expected a whole number of frames");
      announced = n;
      frames_line = number_;
    }
    {
      auto [line, number_] = nextLine("'Frame Time: seconds'");
      auto words = split(line);
      if (words.size() != 3 || words[0] != "Frame" || words[1] != "Time:") {
        fail(number_, "expected 'Frame Time: seconds', found " + quotedInput(line));
      }
      out.frame_time_s = number({words[2], number_}, "Frame Time");
      if (out.frame_time_s <= 0) fail(number_, "expected a positive Frame Time");
    }
    // Every non-blank line from here is a frame, whatever 'Frames:' announced: real files hold
    // more lines than it says (an exporter that counted before the take ended) or fewer (a copy cut
    // short). What is there is read, and the disagreement is told.
    for (; l < lines_.size(); ++l) {
      if (lines_[l].find_first_not_of(" \t\r") == std::string_view::npos) continue;
      const int number_ = static_cast<int>(l) + 1;
      const auto words = split(lines_[l]);
      if (static_cast<int>(words.size()) != out.value_count) {
        fail(number_, fmt::format("frame {} has {} values, expected {} (one per channel)",
                                  out.frames.size() + 1, words.size(), out.value_count));
      }
      out.frame_lines.push_back(number_);
      std::vector<double>& frame = out.frames.emplace_back(words.size());
      for (size_t v = 0; v < words.size(); ++v)
        frame[v] = number({words[v], number_}, "a channel value");
    }
    if (out.frames.empty())
      fail(lastLine(),
           fmt::format("truncated: expected {} frames after 'Frames:', found none", announced));
    if (double(out.frames.size()) != announced) {
      spdlog::warn("{}:{}: 'Frames: {}' announces {} frames, the file holds {}: reading the {}",
                   file_, frames_line, announced, announced, out.frames.size(), out.frames.size());
    }
  }

  std::string file_;
  std::vector<std::string_view> lines_;
  std::vector<Token> tokens_;
  size_t pos_ = 0;
};

Eigen::Matrix3d axisRotation(int axis, double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

Eigen::Vector3d rotationVector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

// Height of the root above the lowest joint (or end site) of a skeleton at rest, along `up`.
double rootHeight(const std::vector<Eigen::Vector3d>& rest, int up) {
  double lowest = rest[0][up];
  for (const auto& p : rest) lowest = std::min(lowest, p[up]);
  return rest[0][up] - lowest;
}

// Bounds on what a file's numbers make: its coordinates (centimetres, usually), and the root's
// place after scaling to the target skeleton, in metres.
constexpr double kMaxCoordinate = 1e7;
constexpr double kMaxRootMetres = 1e4;

struct CmuAlias {
  std::string_view from, to;
};

}  // namespace

std::optional<std::string> humanJointNameFor(std::string_view name, JointNaming naming) {
  // Mixamo (and other FBX exports) prefix a namespace: "mixamorig:Hips".
  if (const size_t colon = name.rfind(':'); colon != std::string_view::npos) {
    name = name.substr(colon + 1);
  }
  static constexpr std::string_view kOurs[] = {
      "pelvis",     "spine1",         "spine2",         "spine3",      "neck",
      "head",       "right_clavicle", "right_shoulder", "right_elbow", "right_wrist",
      "right_hand", "left_clavicle",  "left_shoulder",  "left_elbow",  "left_wrist",
      "left_hand",  "right_hip",      "right_knee",     "right_ankle", "right_foot",
      "left_hip",   "left_knee",      "left_ankle",     "left_foot"};
  for (std::string_view ours : kOurs) {
    if (equalsIgnoreCase(name, ours)) return std::string(ours);
  }
  static constexpr CmuAlias kSpineCmu[] = {
      {"LowerBack", "spine1"}, {"Spine", "spine2"}, {"Spine1", "spine3"}};
  static constexpr CmuAlias kSpineMixamo[] = {
      {"Spine", "spine1"}, {"Spine1", "spine2"}, {"Spine2", "spine3"}};
  static constexpr CmuAlias kSpineBiovision[] = {{"Ab", "spine1"}, {"Chest", "spine3"}};
  std::span<const CmuAlias> spine = kSpineMixamo;
  if (naming == JointNaming::kCmu) spine = kSpineCmu;
  if (naming == JointNaming::kBiovision) spine = kSpineBiovision;
  for (const CmuAlias& a : spine) {
    if (equalsIgnoreCase(name, a.from)) return std::string(a.to);
  }
  static constexpr CmuAlias kSided[] = {
      {"Shoulder", "clavicle"}, {"Collar", "clavicle"}, {"Clavicle", "clavicle"},
      {"Arm", "shoulder"},      {"UpArm", "shoulder"},  {"UpperArm", "shoulder"},
      {"ForeArm", "elbow"},     {"LowArm", "elbow"},    {"LowerArm", "elbow"},
      {"Elbow", "elbow"},       {"Wrist", "wrist"},     {"Hand", "wrist"},
      {"UpLeg", "hip"},         {"Hip", "hip"},         {"Thigh", "hip"},
      {"Leg", "knee"},          {"Knee", "knee"},       {"LowLeg", "knee"},
      {"Shin", "knee"},         {"Foot", "ankle"},      {"Ankle", "ankle"},
      {"ToeBase", "foot"},      {"Toe", "foot"},        {"Toes", "foot"}};
  static constexpr CmuAlias kMiddle[] = {{"Hips", "pelvis"},
                                         {"Pelvis", "pelvis"},
                                         {"Hip", "pelvis"},
                                         {"Neck", "neck"},
                                         {"Head", "head"}};
  for (const CmuAlias& a : kMiddle) {
    if (equalsIgnoreCase(name, a.from)) return std::string(a.to);
  }
  for (auto [prefix, side] : {std::pair{"Right", "right_"}, std::pair{"Left", "left_"}}) {
    const std::string_view p(prefix);
    if (name.size() <= p.size() || !equalsIgnoreCase(name.substr(0, p.size()), p)) continue;
    const std::string_view rest = name.substr(p.size());
    if (naming == JointNaming::kBiovision && equalsIgnoreCase(rest, "Shoulder"))
      return std::string(side) + "shoulder";
    for (const CmuAlias& a : kSided) {
      if (equalsIgnoreCase(rest, a.from)) return std::string(side) + std::string(a.to);
    }
  }
  return std::nullopt;
}

namespace {

// The joints' rest positions in the file's frame (the root at its OFFSET); a skeleton beyond
// kMaxCoordinate is refused.
std::vector<Eigen::Vector3d> restPositionsOf(const BvhFile& bvh, const std::string& file) {
  std::vector<Eigen::Vector3d> rest(bvh.joints.size());
  for (size_t j = 0; j < bvh.joints.size(); ++j) {
    const BvhJoint& joint = bvh.joints[j];
    rest[j] = joint.parent < 0 ? joint.offset : rest[joint.parent] + joint.offset;
    if (!rest[j].allFinite() || rest[j].cwiseAbs().maxCoeff() > kMaxCoordinate) {
      throw Error(locate(file, joint.line, "",
                         fmt::format("joint {} is {} from the origin at rest, expected a skeleton "
                                     "within {:g} units (OFFSETs too large?)",
                                     quotedInput(joint.name), rest[j].norm(), kMaxCoordinate)));
    }
  }
  return rest;
}

// Per target joint, the file's joint that moves it (the first one in file order naming it), or
// -1; a file none of whose joints maps is refused.
std::vector<int> mapJointsOnto(const BvhFile& bvh, const Skeleton& target,
                               const std::string& file) {
  const auto has = [&](std::string_view suffix) {
    return std::any_of(bvh.joints.begin(), bvh.joints.end(), [&](const BvhJoint& j) {
      return j.name.size() >= suffix.size() &&
             equalsIgnoreCase(std::string_view(j.name).substr(j.name.size() - suffix.size()),
                              suffix);
    });
  };
  const JointNaming naming = has("LowerBack") ? JointNaming::kCmu
                             : has("Collar")  ? JointNaming::kBiovision
                                              : JointNaming::kGeneric;
  std::vector<int> source_of(target.jointCount(), -1);
  int mapped = 0;
  for (int j = 0; j < int(bvh.joints.size()); ++j) {
    std::optional<int> t = target.findJoint(bvh.joints[j].name);
    if (!t) {
      if (auto ours = humanJointNameFor(bvh.joints[j].name, naming)) t = target.findJoint(*ours);
    }
    if (t && source_of[*t] < 0) {
      source_of[*t] = j;
      ++mapped;
    }
  }
  if (mapped == 0) {
    throw Error(locate(file, 0, "",
                       fmt::format("no joint of the file maps to the target skeleton (first "
                                   "joint '{}', target root '{}'): expected CMU, Mixamo or our "
                                   "own joint names",
                                   quotedInput(bvh.joints[0].name), target.joint(0).name)));
  }
  return source_of;
}

// The file's rest pose need not be ours (a CMU skeleton's legs splay 20 degrees, a Biovision
// one's arms may hang down): each joint's rotation is taken relative to the turn that brings our
// bone (to its first mapped child) onto the file's at rest (`rest`, turned into our axes by `c`).
// Without it a CMU actor standing straight came in with his thighs turned 20 degrees inward, his
// legs crossed.
std::vector<Eigen::Matrix3d> restTurns(const Skeleton& target, const std::vector<int>& source_of,
                                       const std::vector<Eigen::Vector3d>& rest,
                                       const Eigen::Matrix3d& c) {
  std::vector<Eigen::Matrix3d> rest_turn(target.jointCount(), Eigen::Matrix3d::Identity());
  for (int t = 0; t < target.jointCount(); ++t) {
    if (source_of[t] < 0) continue;
    for (int k = t + 1; k < target.jointCount(); ++k) {
      if (target.joint(k).parent != t || source_of[k] < 0) continue;
      const Eigen::Vector3d ours = target.restPositions()[k] - target.restPositions()[t];
      const Eigen::Vector3d theirs = c * (rest[source_of[k]] - rest[source_of[t]]);
      if (ours.norm() > 1e-9 && theirs.norm() > 1e-9)
        rest_turn[t] = Eigen::Quaterniond::FromTwoVectors(ours, theirs).toRotationMatrix();
      break;
    }
  }
  return rest_turn;
}

}  // namespace

MotionClip loadBvh(const std::filesystem::path& path, const Skeleton& target) {
  const std::string file = path.string();
  const std::string text = readFile(path);
  const BvhFile bvh = Parser(file, text).parse();
  const int source_count = static_cast<int>(bvh.joints.size());
  const std::vector<Eigen::Vector3d> rest = restPositionsOf(bvh, file);
  std::vector<Eigen::Vector3d> rest_with_ends = rest;
  for (const auto& [joint, offset] : bvh.end_sites) {
    rest_with_ends.push_back(rest[joint] + offset);
  }
  const std::vector<int> source_of = mapJointsOnto(bvh, target, file);

  const double source_height = rootHeight(rest_with_ends, 1);
  const double target_height = rootHeight(target.restPositions(), 2);
  if (source_height <= 0 || target_height <= 0) {
    throw Error(locate(file, bvh.joints[0].line, "",
                       "cannot scale the root motion: the rest skeleton has no joint below its "
                       "root, expected a body standing on its legs"));
  }
  const double scale = target_height / source_height;
  const Eigen::Vector3d rest_root(bvh.joints[0].offset.x(), source_height,
                                  bvh.joints[0].offset.z());
  const Eigen::Matrix3d c = yUpToOurs();
  const std::vector<Eigen::Matrix3d> rest_turn = restTurns(target, source_of, rest, c);

  MotionClip clip;
  clip.name = path.stem().string();
  clip.fps = 1.0 / bvh.frame_time_s;
  clip.frames.reserve(bvh.frames.size());
  std::vector<Eigen::Matrix3d> source_global(source_count);
  std::vector<Eigen::Matrix3d> target_global(target.jointCount());
  for (size_t f = 0; f < bvh.frames.size(); ++f) {
    const std::vector<double>& values = bvh.frames[f];
    Eigen::Vector3d root_position = bvh.joints[0].offset;
    for (int j = 0; j < source_count; ++j) {
      const BvhJoint& joint = bvh.joints[j];
      // Channels apply in the order listed: R = R_first · R_second · R_third.
      Eigen::Matrix3d local = Eigen::Matrix3d::Identity();
      bool has_position = false;
      Eigen::Vector3d position = Eigen::Vector3d::Zero();
      for (size_t k = 0; k < joint.channels.size(); ++k) {
        const double v = values[joint.first_value + k];
        const int kind = joint.channels[k];
        if (kind < 3) {
          position[kind] = v;
          has_position = true;
        } else {
          // (Degrees to radians as v * (pi / 180): v * pi overflows for v near the largest double.)
          local = local * axisRotation(kind - 3, v * (std::numbers::pi / 180.0));
        }
      }
      if (j == 0 && has_position) root_position = position;
      source_global[j] = joint.parent < 0 ? local : source_global[joint.parent] * local;
    }
    Pose pose = Pose::rest(target.jointCount());
    pose.root_translation_m = scale * (c * (root_position - rest_root));
    // Values the number check let through (any finite double) must still make a place on a stage:
    // 1e308 overflowed to inf here, and NaN reached truth/joints.csv.
    if (!pose.root_translation_m.allFinite() ||
        pose.root_translation_m.cwiseAbs().maxCoeff() > kMaxRootMetres) {
      throw Error(locate(file, bvh.frame_lines[f], "",
                         fmt::format("frame {}: the root is {} m from the origin, expected a place "
                                     "within {:g} m (a position value too large?)",
                                     f + 1, pose.root_translation_m.norm(), kMaxRootMetres)));
    }
    for (int t = 0; t < target.jointCount(); ++t) {
      const int parent = target.joint(t).parent;
      const Eigen::Matrix3d parent_global =
          parent < 0 ? Eigen::Matrix3d::Identity() : target_global[parent];
      if (source_of[t] < 0) {
        target_global[t] = parent_global;  // no source: stays at zero
        continue;
      }
      target_global[t] = c * source_global[source_of[t]] * c * rest_turn[t];
      const Eigen::Matrix3d local = parent_global.transpose() * target_global[t];
      pose.angles_rad[t] = parent < 0 ? rotationVector(local) : eulerAnglesOf(local);
      if (!pose.angles_rad[t].allFinite()) {
        throw Error(locate(file, bvh.frame_lines[f], "",
                           fmt::format("frame {}: joint {} has no finite rotation (a rotation "
                                       "value too large?)",
                                       f + 1, quotedInput(bvh.joints[source_of[t]].name))));
      }
    }
    clip.frames.push_back(std::move(pose));
  }
  return clip;
}

void saveBvh(const MotionClip& clip, const Skeleton& skeleton, const std::filesystem::path& path) {
  if (!(clip.fps > 0) || !std::isfinite(clip.fps)) {
    throw Error(fmt::format("{}: cannot write clip '{}': fps is {}, expected a positive number",
                            path.string(), clip.name, clip.fps));
  }
  const int n = skeleton.jointCount();
  const Eigen::Matrix3d c = yUpToOurs();
  constexpr double kCm = 100.0;
  // The floor (y = 0) is at our lowest rest joint, as loadBvh measures the root height.
  double lowest = skeleton.restPositions()[0].z();
  for (const auto& p : skeleton.restPositions()) lowest = std::min(lowest, p.z());
  const Eigen::Vector3d floor_shift(0, 0, -lowest);
  auto vec = [](const Eigen::Vector3d& v) {
    // + 0.0 turns -0 into 0: tidier files.
    return fmt::format("{:.10g} {:.10g} {:.10g}", v.x() + 0.0, v.y() + 0.0, v.z() + 0.0);
  };

  std::vector<std::vector<int>> children(n);
  for (int j = 1; j < n; ++j) children[skeleton.joint(j).parent].push_back(j);
  std::string out = "HIERARCHY\n";
  std::vector<int> order;  // joints in file order (depth first)
  auto write = [&](auto&& self, int j, int depth) -> void {
    const std::string indent(2 * depth, ' ');
    const Joint& joint = skeleton.joint(j);
    order.push_back(j);
    const Eigen::Vector3d offset =
        kCm * (c * (j == 0 ? Eigen::Vector3d(joint.offset_m + floor_shift) : joint.offset_m));
    out += fmt::format("{}{} {}\n{}{{\n", indent, j == 0 ? "ROOT" : "JOINT", joint.name, indent);
    out += fmt::format("{}  OFFSET {}\n", indent, vec(offset));
    out += fmt::format("{}  CHANNELS {}{}\n", indent, j == 0 ? 6 : 3,
                       j == 0 ? " Xposition Yposition Zposition Xrotation Yrotation Zrotation"
                              : " Xrotation Yrotation Zrotation");
    for (int child : children[j]) self(self, child, depth + 1);
    if (children[j].empty()) {
      out += fmt::format("{}  End Site\n{}  {{\n{}    OFFSET 0 0 0\n{}  }}\n", indent, indent,
                         indent, indent);
    }
    out += indent + "}\n";
  };
  write(write, 0, 0);
  out +=
      fmt::format("MOTION\nFrames: {}\nFrame Time: {:.10g}\n", clip.frames.size(), 1.0 / clip.fps);
  const double to_deg = 180.0 / std::numbers::pi;
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    const Pose& pose = clip.frames[f];
    if (static_cast<int>(pose.angles_rad.size()) != n) {
      throw Error(
          fmt::format("{}: cannot write clip '{}': frame {} has {} joint angles, expected "
                      "{} (one per joint of the skeleton)",
                      path.string(), clip.name, f, pose.angles_rad.size(), n));
    }
    std::string line;
    for (int j : order) {
      Eigen::Matrix3d local;
      if (j == 0) {
        const Eigen::Vector3d& v = pose.angles_rad[0];
        const double angle = v.norm();
        local = angle > 0 ? Eigen::AngleAxisd(angle, v / angle).toRotationMatrix()
                          : Eigen::Matrix3d::Identity();
        const Eigen::Vector3d position =
            kCm * (c * (skeleton.joint(0).offset_m + pose.root_translation_m + floor_shift));
        line += vec(position) + " ";
      } else {
        local = eulerRotation(pose.angles_rad[j]);
      }
      // A rotation in our frame seen in the file's frame: C R C (C is its own inverse).
      line += vec(eulerAnglesOf(c * local * c) * to_deg);
      line += j == order.back() ? "\n" : " ";
    }
    out += line;
  }
  writeFileAtomically(path, out);
}

}  // namespace lumistage
