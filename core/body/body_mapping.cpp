#include "core/body/body_mapping.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <map>
#include <optional>
#include <utility>

#include "core/base/error.h"
#include "core/body/bvh.h"
#include "core/body/mesh_io.h"

namespace lumistage {

namespace {

using Eigen::Vector3d;
using JointArray = std::array<int, kHumanJointCount>;

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Lowercase words of a name, split at anything not a letter or digit:
// "Skeleton_arm_joint_R__2_" -> skeleton, arm, joint, r, 2.
std::vector<std::string> words(std::string_view name) {
  std::vector<std::string> out;
  std::string word;
  for (char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      word += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!word.empty()) {
      out.push_back(std::move(word));
      word.clear();
    }
  }
  if (!word.empty()) out.push_back(std::move(word));
  return out;
}

// The file's hierarchy, for walking bone chains.
struct FileTree {
  explicit FileTree(const Skeleton& s)
      : skeleton(s), children(s.jointCount()), depth(s.jointCount()) {
    for (int j = 0; j < s.jointCount(); ++j) {
      const int p = s.joint(j).parent;
      depth[j] = p < 0 ? 0 : depth[p] + 1;
      if (p >= 0) children[p].push_back(j);
    }
    for (int j = 0; j < s.jointCount(); ++j)
      if (children[j].empty()) leaves.push_back(j);
  }
  const Vector3d& at(int j) const { return skeleton.restPositions()[j]; }
  int parent(int j) const { return skeleton.joint(j).parent; }
  bool isAncestor(int a, int b) const {  // a is a proper ancestor of b
    for (b = parent(b); b >= 0; b = parent(b))
      if (b == a) return true;
    return false;
  }
  int lca(int a, int b) const {
    while (depth[a] > depth[b]) a = parent(a);
    while (depth[b] > depth[a]) b = parent(b);
    while (a != b) a = parent(a), b = parent(b);
    return a;
  }
  // The joints from `from` (left out) down to `to` (included).
  std::vector<int> pathDown(int from, int to) const {
    std::vector<int> path;
    for (int j = to; j >= 0 && j != from; j = parent(j)) path.push_back(j);
    std::reverse(path.begin(), path.end());
    return path;
  }

  const Skeleton& skeleton;
  std::vector<std::vector<int>> children;
  std::vector<int> depth;
  std::vector<int> leaves;
};

// Rigify/metarig and Unreal names: "thigh.L", "DEF-upper_arm.R", "spine.003", "calf_l".
std::optional<std::string> rigifyName(std::string_view name, bool rigify_spine) {
  std::string n = lower(name);
  for (std::string_view prefix : {"def-", "org-"})
    if (n.rfind(prefix, 0) == 0) n = n.substr(prefix.size());
  if (rigify_spine) {
    static const std::map<std::string, std::string> kSpine = {
        {"spine", "pelvis"},     {"spine.001", "spine1"}, {"spine.002", "spine2"},
        {"spine.003", "spine3"}, {"spine.004", "neck"},   {"spine.006", "head"}};
    if (auto it = kSpine.find(n); it != kSpine.end()) return it->second;
  }
  if (n.size() < 3 || (n[n.size() - 2] != '.' && n[n.size() - 2] != '_')) return std::nullopt;
  const char side = n.back();
  if (side != 'l' && side != 'r') return std::nullopt;
  static const std::map<std::string, std::string> kSided = {
      {"thigh", "hip"},         {"shin", "knee"},         {"calf", "knee"},
      {"foot", "ankle"},        {"toe", "foot"},          {"ball", "foot"},
      {"shoulder", "clavicle"}, {"clavicle", "clavicle"}, {"upper_arm", "shoulder"},
      {"upperarm", "shoulder"}, {"forearm", "elbow"},     {"lowerarm", "elbow"},
      {"hand", "wrist"},        {"upper_leg", "hip"},     {"lower_leg", "knee"},
      {"upperleg", "hip"},      {"lowerleg", "knee"}};
  const auto it = kSided.find(n.substr(0, n.size() - 2));
  if (it == kSided.end()) return std::nullopt;
  return std::string(side == 'l' ? "left_" : "right_") + it->second;
}

// Names that tell a limb and a side but not the joint (CesiumMan's "leg_joint_R_2",
// "Skeleton_arm_joint_L__3_", "Skeleton_torso_joint_1"): the joints of one chain, in hierarchy
// order, are its joints from the body outward. Chains whose joints are not one line are left out.
void mapByNameChains(const FileTree& tree, JointArray& out) {
  std::map<std::string, std::vector<int>> chains;
  for (int j = 0; j < tree.skeleton.jointCount(); ++j) {
    const std::vector<std::string> w = words(tree.skeleton.joint(j).name);
    const auto has = [&](std::string_view word) {
      return std::find(w.begin(), w.end(), word) != w.end();
    };
    const bool numbered = has("joint") || std::any_of(w.begin(), w.end(), [](const std::string& x) {
                            return std::all_of(x.begin(), x.end(), ::isdigit);
                          });
    if (!numbered) continue;
    const std::string side = has("l") || has("left")    ? "left_"
                             : has("r") || has("right") ? "right_"
                                                        : "";
    for (std::string_view limb : {"leg", "arm", "torso", "neck"}) {
      const bool sided = limb == "leg" || limb == "arm";
      if (has(limb) && sided == !side.empty()) chains[side + std::string(limb)].push_back(j);
    }
  }
  for (auto& [chain, joints] : chains) {
    std::sort(joints.begin(), joints.end(),
              [&](int a, int b) { return tree.depth[a] < tree.depth[b]; });
    bool line = true;
    for (size_t i = 1; i < joints.size(); ++i)
      line = line && tree.isAncestor(joints[i - 1], joints[i]);
    if (!line) continue;
    const auto assign = [&](std::initializer_list<int> ours) {
      size_t i = 0;
      for (int t : ours) {
        if (i < joints.size() && out[t] < 0) out[t] = joints[i];
        ++i;
      }
    };
    const bool right = chain.rfind("right_", 0) == 0;
    if (chain.ends_with("leg")) {
      assign(right ? std::initializer_list<int>{kRightHip, kRightKnee, kRightAnkle, kRightFoot}
                   : std::initializer_list<int>{kLeftHip, kLeftKnee, kLeftAnkle, kLeftFoot});
    } else if (chain.ends_with("arm")) {
      assign(right
                 ? std::initializer_list<int>{kRightShoulder, kRightElbow, kRightWrist, kRightHand}
                 : std::initializer_list<int>{kLeftShoulder, kLeftElbow, kLeftWrist, kLeftHand});
    } else if (chain == "torso") {
      if (out[kPelvis] < 0) out[kPelvis] = joints.front();
      if (joints.size() >= 2 && out[kSpine3] < 0) out[kSpine3] = joints.back();
      if (joints.size() >= 3 && out[kSpine1] < 0) out[kSpine1] = joints[1];
      if (joints.size() >= 4 && out[kSpine2] < 0) out[kSpine2] = joints[2];
    } else if (chain == "neck") {
      assign({kNeck, kHead});
    }
  }
}

// The path's index h where two bones in a row, path[h]->path[h+1]->path[h+2], are longest (the
// upper arm and forearm, the thigh and shin); -1 when the path has fewer than three joints.
int longestTwoBones(const FileTree& tree, const std::vector<int>& path) {
  int best = -1;
  double best_length = -1;
  for (size_t h = 0; h + 2 < path.size(); ++h) {
    const double length = (tree.at(path[h + 1]) - tree.at(path[h])).norm() +
                          (tree.at(path[h + 2]) - tree.at(path[h + 1])).norm();
    if (length > best_length) best = static_cast<int>(h), best_length = length;
  }
  return best;
}

struct Geometry {
  JointArray joint;
  std::string problem;  // why it stopped short, empty when it did not
};

// Our limb joints on a chain: the two longest bones in a row end at the middle and outer joint.
// Returns false when the chain is too short.
bool mapLimb(const FileTree& tree, const std::vector<int>& path, int first_ours, int before_ours,
             JointArray& out) {
  const int h = longestTwoBones(tree, path);
  if (h < 0) return false;
  for (int k = 0; k < 4 && h + k < static_cast<int>(path.size()); ++k)
    out[first_ours + k] = path[h + k];
  if (before_ours >= 0 && h >= 1) out[before_ours] = path[h - 1];
  return true;
}

// The bone chains by position: the feet are the lowest end joints on either side, the head the
// highest, the pelvis where their chains meet, the hands the end joints farthest to either side.
Geometry mapByGeometry(const FileTree& tree) {
  Geometry g;
  g.joint.fill(-1);
  const auto& leaves = tree.leaves;
  double mid_x = 0, lo = 1e30, hi = -1e30;
  for (const Vector3d& p : tree.skeleton.restPositions()) {
    mid_x += p.x() / tree.skeleton.jointCount();
    lo = std::min(lo, p.z());
    hi = std::max(hi, p.z());
  }
  const double height = hi - lo;
  const auto lowest = [&](auto&& accept) {
    int best = -1;
    for (int l : leaves)
      if (accept(l) && (best < 0 || tree.at(l).z() < tree.at(best).z())) best = l;
    return best;
  };
  const int foot_a = lowest([](int) { return true; });
  const bool a_right = tree.at(foot_a).x() > mid_x;
  const int foot_b = lowest(
      [&](int l) { return (tree.at(l).x() > mid_x) != a_right && tree.lca(l, foot_a) != l; });
  if (foot_b < 0 || tree.at(foot_b).z() - tree.at(foot_a).z() > 0.2 * height) {
    g.problem = "no two legs (end joints at the bottom on either side of the body)";
    return g;
  }
  int head = -1;
  for (int l : leaves)
    if (head < 0 || tree.at(l).z() > tree.at(head).z()) head = l;
  const int legs = tree.lca(foot_a, foot_b);
  const int pelvis = tree.isAncestor(legs, head) ? legs : tree.lca(legs, head);
  // Legs reach down from the pelvis (a legless body's hands would pass for feet otherwise).
  if (tree.at(pelvis).z() - tree.at(foot_a).z() < (tree.at(head).z() - tree.at(foot_a).z()) / 3) {
    g.problem = "no two legs (end joints at the bottom on either side, well below where they meet)";
    return g;
  }
  g.joint[kPelvis] = pelvis;
  for (int foot : {foot_a, foot_b}) {
    const std::vector<int> path = tree.pathDown(pelvis, foot);
    const bool right = tree.at(path.empty() ? foot : path.front()).x() > tree.at(pelvis).x();
    if (!mapLimb(tree, path, right ? kRightHip : kLeftHip, -1, g.joint)) {
      g.problem = fmt::format("the {} leg has fewer than three joints", right ? "right" : "left");
      return g;
    }
  }
  // Arms: the end joints farthest to either side, not in a leg.
  const auto in_leg = [&](int l) {
    for (int foot : {foot_a, foot_b}) {
      const std::vector<int> path = tree.pathDown(pelvis, foot);
      if (!path.empty() && (l == path.front() || tree.isAncestor(path.front(), l))) return true;
    }
    return false;
  };
  const std::vector<int> spine = tree.pathDown(pelvis, head);
  int branch = -1;
  for (bool right : {true, false}) {
    int hand = -1;
    for (int l : leaves) {
      if (l == head || in_leg(l)) continue;
      const double out = (tree.at(l).x() - tree.at(pelvis).x()) * (right ? 1 : -1);
      if (out > 0.08 * height &&
          (hand < 0 || out > (tree.at(hand).x() - tree.at(pelvis).x()) * (right ? 1 : -1)))
        hand = l;
    }
    if (hand < 0) {
      g.problem = fmt::format("no {} arm (an end joint out to that side above the legs)",
                              right ? "right" : "left");
      return g;
    }
    const int from = tree.lca(hand, head);
    if (branch < 0 || tree.depth[from] > tree.depth[branch]) branch = from;
    if (!mapLimb(tree, tree.pathDown(from, hand), right ? kRightShoulder : kLeftShoulder,
                 right ? kRightClavicle : kLeftClavicle, g.joint)) {
      g.problem = fmt::format("the {} arm has fewer than three joints", right ? "right" : "left");
      return g;
    }
  }
  if (branch == pelvis) return g;  // arms from the pelvis: no spine to speak of
  g.joint[kSpine3] = branch;
  // Between the pelvis and the arms' branch: spine1 and spine2 by height (ours stand at 0.29 and
  // 0.63 of the way); above it the neck, then the head (the joint before an end joint).
  std::vector<int> between, above;
  for (int j : spine) {
    if (j == branch) continue;
    (tree.isAncestor(j, branch) ? between : above).push_back(j);
  }
  const double span = (tree.at(branch) - tree.at(pelvis)).norm();
  for (auto [ours, fraction] : {std::pair{kSpine1, 0.29}, std::pair{kSpine2, 0.63}}) {
    int best = -1;
    double best_error = 1e30;
    for (int j : between) {
      const double error = std::abs((tree.at(j) - tree.at(pelvis)).norm() / span - fraction);
      if (j != g.joint[kSpine1] && error < best_error) best = j, best_error = error;
    }
    g.joint[ours] = best;
  }
  if (above.size() == 1) g.joint[kHead] = above[0];
  if (above.size() >= 2) {
    g.joint[kNeck] = above[0];
    g.joint[kHead] = above.size() == 2 ? above[1] : above[above.size() - 2];
  }
  return g;
}

constexpr std::array<int, 13> kRequired = {
    kPelvis,        kRightHip,   kRightKnee,  kRightAnkle,   kLeftHip,   kLeftKnee, kLeftAnkle,
    kRightShoulder, kRightElbow, kRightWrist, kLeftShoulder, kLeftElbow, kLeftWrist};

}  // namespace

const char* jointFoundName(JointFound how) {
  switch (how) {
    case JointFound::kName:
      return "name";
    case JointFound::kNameChain:
      return "name and chain order";
    case JointFound::kGeometry:
      return "bone chains by position";
    case JointFound::kPlaced:
      return "none: placed between its neighbours";
  }
  return "?";
}

BodyMapping mapHumanJoints(const Skeleton& file_skeleton, std::string_view source) {
  const FileTree tree(file_skeleton);
  const Skeleton human = makeHumanSkeleton();
  const int n = file_skeleton.jointCount();
  const auto has = [&](std::string_view suffix) {
    for (const Joint& j : file_skeleton.joints())
      if (lower(j.name).ends_with(suffix)) return true;
    return false;
  };
  const JointNaming naming = has("lowerback") ? JointNaming::kCmu
                             : has("collar")  ? JointNaming::kBiovision
                                              : JointNaming::kGeneric;
  const bool rigify_spine = has("spine.001");
  JointArray named, chained;
  named.fill(-1);
  chained.fill(-1);
  for (int j = 0; j < n; ++j) {
    const std::string& name = file_skeleton.joint(j).name;
    std::optional<std::string> ours = rigifyName(name, rigify_spine);
    if (!ours) ours = humanJointNameFor(name, naming);
    if (!ours) continue;
    if (const std::optional<int> t = human.findJoint(*ours); t && named[*t] < 0) named[*t] = j;
  }
  mapByNameChains(tree, chained);
  const Geometry geometry = mapByGeometry(tree);

  BodyMapping m;
  m.file_joint.assign(kHumanJointCount, -1);
  m.how.assign(kHumanJointCount, JointFound::kPlaced);
  std::vector<bool> used(n, false);
  for (auto [found, how] : {std::pair{&std::as_const(named), JointFound::kName},
                            std::pair{&std::as_const(chained), JointFound::kNameChain},
                            std::pair{&geometry.joint, JointFound::kGeometry}}) {
    for (int t = 0; t < kHumanJointCount; ++t) {
      const int f = (*found)[t];
      if (m.file_joint[t] >= 0 || f < 0 || used[f]) continue;
      m.file_joint[t] = f;
      m.how[t] = how;
      used[f] = true;
    }
  }
  for (int t : kRequired) {
    if (m.file_joint[t] >= 0) continue;
    throw Error(fmt::format(
        "{}: cannot map the body onto the human skeleton: no joint for {} by "
        "name, and by the bone chains: {}",
        source, human.joint(t).name, geometry.problem.empty() ? "none found" : geometry.problem));
  }
  // Each mapped joint must lie below the joint its nearest mapped ancestor of ours maps to.
  for (int t = 1; t < kHumanJointCount; ++t) {
    if (m.file_joint[t] < 0) continue;
    int a = human.joint(t).parent;
    while (a >= 0 && m.file_joint[a] < 0) a = human.joint(a).parent;
    if (a < 0 || tree.isAncestor(m.file_joint[a], m.file_joint[t])) continue;
    throw Error(fmt::format(
        "{}: cannot map the body onto the human skeleton: {} is joint '{}' ({}) and {} is '{}' "
        "({}), which is not below it in the file's hierarchy",
        source, human.joint(t).name, file_skeleton.joint(m.file_joint[t]).name,
        jointFoundName(m.how[t]), human.joint(a).name, file_skeleton.joint(m.file_joint[a]).name,
        jointFoundName(m.how[a])));
  }
  m.weights_to.assign(n, kPelvis);
  std::vector<int> ours_of(n, -1);
  for (int t = 0; t < kHumanJointCount; ++t)
    if (m.file_joint[t] >= 0) ours_of[m.file_joint[t]] = t;
  for (int j = 0; j < n; ++j) {  // parents come first
    const int p = file_skeleton.joint(j).parent;
    m.weights_to[j] = ours_of[j] >= 0                                       ? ours_of[j]
                      : p >= 0 && tree.isAncestor(m.file_joint[kPelvis], j) ? m.weights_to[p]
                                                                            : kPelvis;
  }
  return m;
}

std::string describeBodyMapping(const BodyMapping& mapping, const Skeleton& file_skeleton) {
  const Skeleton human = makeHumanSkeleton();
  std::string out = "mapped onto the human skeleton:\n";
  for (int t = 0; t < kHumanJointCount; ++t) {
    const int f = mapping.file_joint[t];
    out += fmt::format("  {:<15} <- {:<28} ({})\n", human.joint(t).name,
                       f < 0 ? "-" : file_skeleton.joint(f).name, jointFoundName(mapping.how[t]));
  }
  std::vector<bool> mapped(file_skeleton.jointCount(), false);
  for (int f : mapping.file_joint)
    if (f >= 0) mapped[f] = true;
  std::string unmapped;
  for (int j = 0; j < file_skeleton.jointCount(); ++j) {
    if (mapped[j]) continue;
    unmapped += fmt::format("  {} (its weights to {})\n", file_skeleton.joint(j).name,
                            human.joint(mapping.weights_to[j]).name);
  }
  out += unmapped.empty() ? "every file joint is one of ours\n"
                          : "file joints that are none of ours:\n" + unmapped;
  return out;
}

namespace {

// The generic human's rest positions (the directions and proportions of our rest pose).
const std::vector<Vector3d>& genericRest() {
  static const Skeleton human = makeHumanSkeleton();
  return human.restPositions();
}

// Our first mapped joint down the chain of first children below t (the bone t turns), or -1.
int boneEnd(const Skeleton& human, const BodyMapping& mapping, int t) {
  for (int j = t;;) {
    int child = -1;
    for (int k = j + 1; k < human.jointCount() && child < 0; ++k)
      if (human.joint(k).parent == j) child = k;
    if (child < 0) return -1;
    if (mapping.file_joint[child] >= 0) return child;
    j = child;
  }
}

// Length along the chain of first children from a to its descendant d, in the generic human.
double chainLength(const Skeleton& human, int a, int d) {
  double length = 0;
  for (int j = d; j != a && j >= 0; j = human.joint(j).parent)
    length += (genericRest()[j] - genericRest()[human.joint(j).parent]).norm();
  return length;
}

// Our joints at the file's bind pose (`at`), each joint's turn from the file's bind pose to our
// rest pose (`turn`) and its place at our rest pose (`rest`).
struct Reposing {
  std::vector<Vector3d> at, rest;
  std::vector<Eigen::Matrix3d> turn;
};

Reposing reposeJoints(const Skeleton& file_skeleton, const BodyMapping& m) {
  const Skeleton human = makeHumanSkeleton();
  const auto& g = genericRest();
  const auto file_at = [&](int t) { return file_skeleton.restPositions()[m.file_joint[t]]; };
  // The file's size against ours, by the legs (thigh and shin), for joints placed beyond the
  // file's.
  double file_legs = 0, our_legs = 0;
  for (int hip : {kRightHip, kLeftHip}) {
    file_legs +=
        (file_at(hip + 1) - file_at(hip)).norm() + (file_at(hip + 2) - file_at(hip + 1)).norm();
    our_legs += (g[hip + 1] - g[hip]).norm() + (g[hip + 2] - g[hip + 1]).norm();
  }
  const double scale = file_legs / our_legs;
  Reposing r;
  r.at.resize(kHumanJointCount);
  r.rest.resize(kHumanJointCount);
  r.turn.assign(kHumanJointCount, Eigen::Matrix3d::Identity());
  for (int t = 0; t < kHumanJointCount; ++t) {
    const int a = human.joint(t).parent;
    const Eigen::Matrix3d parent_turn = a < 0 ? Eigen::Matrix3d::Identity() : r.turn[a];
    if (m.file_joint[t] >= 0) {
      r.at[t] = file_at(t);
    } else if (const int d = boneEnd(human, m, t); d >= 0) {
      // Between its parent and its first mapped descendant, as far along as ours is.
      const double fraction = chainLength(human, a, t) / chainLength(human, a, d);
      r.at[t] = r.at[a] + fraction * (file_at(d) - r.at[a]);
    } else {
      // Beyond the file's joints (a hand, a foot, the head): our offset at the file's size,
      // turned back into the file's pose.
      r.at[t] = r.at[a] + parent_turn.transpose() * (scale * (g[t] - g[a]));
    }
    r.turn[t] = parent_turn;
    if (m.file_joint[t] >= 0) {
      if (const int d = boneEnd(human, m, t); d >= 0) {
        const Vector3d theirs = file_at(d) - r.at[t], ours = g[d] - g[t];
        if (theirs.norm() > 1e-9)
          r.turn[t] = Eigen::Quaterniond::FromTwoVectors(theirs, ours).toRotationMatrix();
      }
    }
    r.rest[t] = a < 0 ? r.at[t] : Vector3d(r.rest[a] + r.turn[a] * (r.at[t] - r.at[a]));
  }
  return r;
}

// The file's skin weights moved onto our joints: merged, the four largest kept, renormalised.
SkinWeights moveWeights(const SkinWeights& file_skin, const BodyMapping& m) {
  SkinWeights out;
  const size_t n = file_skin.joints.size();
  out.joints.resize(n);
  out.weights.resize(n);
  for (size_t v = 0; v < n; ++v) {
    std::array<float, kHumanJointCount> w{};
    for (int k = 0; k < kMaxInfluences; ++k)
      w[m.weights_to[file_skin.joints[v][k]]] += file_skin.weights[v][k];
    std::array<int, kHumanJointCount> order;
    for (int t = 0; t < kHumanJointCount; ++t) order[t] = t;
    std::partial_sort(order.begin(), order.begin() + kMaxInfluences, order.end(),
                      [&](int a, int b) { return w[a] > w[b]; });
    float sum = 0;
    for (int k = 0; k < kMaxInfluences; ++k) sum += w[order[k]];
    for (int k = 0; k < kMaxInfluences; ++k) {
      const bool used = w[order[k]] > 0 && sum > 0;
      out.joints[v][k] = static_cast<uint16_t>(used ? order[k] : 0);
      out.weights[v][k] = used ? w[order[k]] / sum : 0.0f;
    }
    if (!(sum > 0)) out.weights[v][0] = 1.0f;  // the pelvis carries a vertex without weights
  }
  return out;
}

}  // namespace

SkinnedMesh fitToHumanSkeleton(const SkinnedMesh& file_body, const BodyMapping& mapping,
                               std::string_view source) {
  const Reposing r = reposeJoints(file_body.skeleton, mapping);
  SkinnedMesh out;
  out.skin = moveWeights(file_body.skin, mapping);
  const int n = file_body.rest.vertexCount();
  out.rest.positions.resize(3, n);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = file_body.rest.positions.col(v).cast<double>();
    Vector3d q = Vector3d::Zero();
    for (int k = 0; k < kMaxInfluences; ++k) {
      const int t = out.skin.joints[v][k];
      q += out.skin.weights[v][k] * (r.turn[t] * (p - r.at[t]) + r.rest[t]);
    }
    out.rest.positions.col(v) = q.cast<float>();
  }
  // Standing on the floor.
  const float floor = n > 0 ? out.rest.positions.row(2).minCoeff() : 0.0f;
  out.rest.positions.row(2).array() -= floor;
  std::vector<Joint> joints = makeHumanSkeleton().joints();
  for (int t = 0; t < kHumanJointCount; ++t) {
    const int a = joints[t].parent;
    joints[t].offset_m =
        a < 0 ? Vector3d(r.rest[t] - Vector3d(0, 0, floor)) : Vector3d(r.rest[t] - r.rest[a]);
  }
  out.skeleton = Skeleton(std::move(joints));
  out.rest.triangles = file_body.rest.triangles;
  out.rest.computeNormals();
  int without = 0;
  for (int v = 0; v < n; ++v) {
    if (out.rest.normals.col(v).squaredNorm() > 0.5f) continue;
    ++without;
    const int t = out.skin.joints[v][0];
    Eigen::Vector3f d = out.rest.positions.col(v) - out.skeleton.restPositions()[t].cast<float>();
    out.rest.normals.col(v) =
        d.norm() > 0 ? Eigen::Vector3f(d.normalized()) : Eigen::Vector3f::UnitZ();
  }
  if (without > 0)
    spdlog::warn("{}: {} vertices are in no triangle: their normals point away from their joint",
                 source, without);
  if (const Status closed = checkClosedManifold(out.rest); !closed.ok())
    spdlog::warn(
        "{}: the mesh is not closed and manifold ({}): refinement and rendering see "
        "through its holes",
        source, closed.error());
  out.validate();
  return out;
}

SkinnedMesh loadHumanBody(const std::filesystem::path& path, BodyMapping* mapping) {
  const SkinnedMesh file_body = loadSkinnedMesh(path);
  const BodyMapping m = mapHumanJoints(file_body.skeleton, path.string());
  SkinnedMesh body = fitToHumanSkeleton(file_body, m, path.string());
  if (mapping) *mapping = m;
  return body;
}

}  // namespace lumistage
