#include "core/body/human_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/base/child_process.h"
#include "core/base/error.h"
#include "core/base/resource_path.h"
#include "core/body/body_mapping.h"
#include "core/body/mesh_io.h"
#include "core/body/surface_nets.h"

namespace lumistage {

namespace {

using V3 = Eigen::Vector3f;

// One piece of the body: a capsule whose radius tapers from a to b, or an ellipsoid (b unused).
struct Primitive {
  enum Kind { kCapsule, kEllipsoid } kind;
  int joint;  // the joint whose rotation moves this piece
  Material material;
  V3 a, b;
  float ra = 0, rb = 0;   // capsule radii at a and b
  V3 radii = V3::Zero();  // ellipsoid radii

  float distance(const V3& p) const {
    if (kind == kCapsule) {
      const V3 ab = b - a;
      const float t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f);
      return (p - (a + t * ab)).norm() - (ra + t * (rb - ra));
    }
    // A close bound of the ellipsoid's distance (exact on the axes).
    const V3 q = p - a;
    const float k0 = (q.array() / radii.array()).matrix().norm();
    const float k1 = (q.array() / (radii.array() * radii.array())).matrix().norm();
    return k1 > 0 ? k0 * (k0 - 1) / k1 : -radii.minCoeff();
  }
};

// Polynomial smooth minimum: blends shapes within k of each other (armpits, crotch, neck).
float smoothMin(float a, float b, float k) {
  const float h = std::clamp(0.5f + 0.5f * (b - a) / k, 0.0f, 1.0f);
  return b + h * (a - b) - k * h * (1 - h);
}

std::vector<Primitive> bodyPrimitives(const Skeleton& skeleton, const HumanModelSpec& spec) {
  const BodyShape& shape = spec.shape;
  const auto& r = skeleton.restPositions();
  auto at = [&](int j) -> V3 { return r[j].cast<float>(); };
  const float s = float(shape.height_m / 1.75), g = s * float(shape.girth_scale);
  const float belly = float(shape.belly_scale);
  std::vector<Primitive> p;
  auto capsule = [&](int joint, V3 a, V3 b, float ra, float rb, Material m = Material::kSkin) {
    p.push_back({Primitive::kCapsule, joint, m, a, b, ra, rb, V3::Zero()});
  };
  auto ellipsoid = [&](int joint, V3 c, V3 radii, Material m = Material::kSkin) {
    p.push_back({Primitive::kEllipsoid, joint, m, c, c, 0, 0, radii});
  };
  // Torso: pelvis, waist, chest and shoulders as ellipsoids, wider than deep.
  ellipsoid(kPelvis, at(kPelvis) + V3(0, -0.01f, -0.02f) * s, V3(0.165f, 0.11f, 0.12f) * g);
  ellipsoid(kSpine1, at(kSpine1) + V3(0, 0.0f, 0.03f) * s,
            V3(0.15f * belly, 0.105f * belly, 0.12f) * g);
  ellipsoid(kSpine2, at(kSpine2) + V3(0, 0.005f, 0.06f) * s, V3(0.165f, 0.11f, 0.13f) * g);
  ellipsoid(kSpine3, at(kSpine3) + V3(0, 0.0f, 0.06f) * s, V3(0.185f, 0.105f, 0.11f) * g);
  capsule(kNeck, at(kNeck) - V3(0, 0, 0.03f) * s, at(kHead) + V3(0, 0, 0.02f) * s, 0.055f * g,
          0.05f * g);
  ellipsoid(kHead, at(kHead) + V3(0, 0.015f, 0.085f) * s, V3(0.078f, 0.095f, 0.11f) * s);
  for (int side = 0; side < 2; ++side) {
    const int c = side == 0 ? kRightClavicle : kLeftClavicle;
    const int sh = c + 1, el = c + 2, wr = c + 3, ha = c + 4;
    capsule(c, at(c), at(sh), 0.06f * g, 0.06f * g);
    capsule(sh, at(sh), at(el), 0.05f * g, 0.04f * g);
    capsule(el, at(el), at(wr), 0.04f * g, 0.03f * g);
    capsule(wr, at(wr), at(ha), 0.035f * g, 0.03f * g);
    const int hip = side == 0 ? kRightHip : kLeftHip;
    const int kn = hip + 1, an = hip + 2, ft = hip + 3;
    capsule(hip, at(hip), at(kn), 0.085f * g, 0.055f * g);
    capsule(kn, at(kn), at(an), 0.05f * g, 0.035f * g);
    capsule(an, at(an) + V3(0, -0.03f, -0.02f) * s, at(ft) + V3(0, 0, 0.005f) * s, 0.04f * g,
            0.03f * g);
  }
  if (spec.clothing) {
    // Loose shirt over the torso and upper arms, with a hem below the waist.
    ellipsoid(kSpine1, at(kSpine1) + V3(0, 0.0f, 0.0f) * s,
              V3(0.175f * belly, 0.13f * belly, 0.16f) * g, Material::kShirt);
    ellipsoid(kSpine2, at(kSpine2) + V3(0, 0.01f, 0.06f) * s, V3(0.18f, 0.13f, 0.15f) * g,
              Material::kShirt);
    ellipsoid(kSpine3, at(kSpine3) + V3(0, 0.0f, 0.05f) * s, V3(0.2f, 0.12f, 0.12f) * g,
              Material::kShirt);
    for (int side = 0; side < 2; ++side) {
      const int c = side == 0 ? kRightClavicle : kLeftClavicle;
      const V3 sleeve_end = at(c + 1) + 0.55f * (at(c + 2) - at(c + 1));
      capsule(c, at(c), at(c + 1), 0.07f * g, 0.068f * g, Material::kShirt);
      capsule(c + 1, at(c + 1), sleeve_end, 0.065f * g, 0.058f * g, Material::kShirt);
      // Trousers: wider legs, flaring a little at the ankle.
      const int hip = side == 0 ? kRightHip : kLeftHip;
      capsule(hip, at(hip) + V3(0, 0, 0.02f) * s, at(hip + 1), 0.1f * g, 0.07f * g,
              Material::kTrousers);
      capsule(hip + 1, at(hip + 1), at(hip + 2) + V3(0, 0, 0.03f) * s, 0.068f * g, 0.06f * g,
              Material::kTrousers);
      // Shoes.
      capsule(hip + 2, at(hip + 2) + V3(0, -0.04f, -0.03f) * s,
              at(hip + 3) + V3(0, 0.01f, 0.0f) * s, 0.05f * g, 0.04f * g, Material::kShoes);
    }
    ellipsoid(kPelvis, at(kPelvis) + V3(0, -0.01f, -0.02f) * s, V3(0.18f, 0.125f, 0.135f) * g,
              Material::kTrousers);
    // Hair: a cap over the top and back of the head.
    ellipsoid(kHead, at(kHead) + V3(0, -0.005f, 0.1f) * s, V3(0.088f, 0.105f, 0.105f) * s,
              Material::kHair);
  }
  return p;
}

}  // namespace

SkinnedMesh makeHumanModel(const HumanModelSpec& spec) {
  SkinnedMesh out;
  out.skeleton = makeHumanSkeleton(spec.shape);
  const std::vector<Primitive> primitives = bodyPrimitives(out.skeleton, spec);
  const float k = 0.03f * float(spec.shape.height_m / 1.75);
  auto sdf = [&](const V3& p) {
    float d = primitives[0].distance(p);
    for (size_t i = 1; i < primitives.size(); ++i) d = smoothMin(d, primitives[i].distance(p), k);
    return d;
  };
  Eigen::AlignedBox3f bounds;
  for (const Eigen::Vector3d& j : out.skeleton.restPositions()) bounds.extend(j.cast<float>());
  bounds.min() -= V3::Constant(0.25f);
  bounds.max() += V3::Constant(0.3f);

  // Surface nets give about area / cell² vertices: start from a guess, correct once.
  float cell = 0.032f * float(spec.shape.height_m / 1.75);
  TriangleMesh mesh = extractSurface(sdf, bounds, cell);
  cell *= std::sqrt(float(mesh.vertexCount()) / float(std::max(spec.target_vertices, 100)));
  mesh = extractSurface(sdf, bounds, cell);

  // Skinning weights: each joint's distance is that of its nearest piece; the nearest joint and
  // its parent and children may share the vertex, with weights falling off over a few cm.
  const int joint_count = out.skeleton.jointCount();
  std::vector<std::set<int>> neighbours(joint_count);
  for (int j = 0; j < joint_count; ++j) {
    neighbours[j].insert(j);
    const int parent = out.skeleton.joint(j).parent;
    if (parent >= 0) {
      neighbours[j].insert(parent);
      neighbours[parent].insert(j);
    }
  }
  const int n = mesh.vertexCount();
  std::vector<std::vector<float>> weights(n, std::vector<float>(joint_count, 0.0f));
  out.materials.resize(n);
  const float falloff = 0.02f * float(spec.shape.height_m / 1.75);
  std::vector<float> joint_distance(joint_count);
  std::vector<int> nearest_joint(n);
  for (int v = 0; v < n; ++v) {
    const V3 p = mesh.positions.col(v);
    std::fill(joint_distance.begin(), joint_distance.end(), 1e9f);
    float best = 1e9f;
    int best_joint = 0;
    Material material = Material::kSkin;
    for (const Primitive& prim : primitives) {
      const float d = prim.distance(p);
      joint_distance[prim.joint] = std::min(joint_distance[prim.joint], d);
      if (d < best) {
        best = d;
        best_joint = prim.joint;
        material = prim.material;
      }
    }
    out.materials[v] = static_cast<uint8_t>(material);
    nearest_joint[v] = best_joint;
    for (int j : neighbours[best_joint]) {
      weights[v][j] = std::exp(-(joint_distance[j] - best) / falloff);
    }
  }
  // Smooth over the mesh (a few rounds of neighbour averaging) so that weights change gradually
  // where the nearest bone changes; each round keeps a vertex to its nearest joint's neighbours,
  // or smoothing would leak across the crotch from one leg to the other.
  std::vector<std::vector<int>> adjacency(n);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) adjacency[t[e]].push_back(t[(e + 1) % 3]);
  }
  for (int round = 0; round < 4; ++round) {
    std::vector<std::vector<float>> next = weights;
    for (int v = 0; v < n; ++v) {
      for (int nb : adjacency[v]) {
        for (int j = 0; j < joint_count; ++j) next[v][j] += weights[nb][j];
      }
      float sum = 0;
      for (int j = 0; j < joint_count; ++j) {
        if (!neighbours[nearest_joint[v]].count(j)) next[v][j] = 0.0f;
        sum += next[v][j];
      }
      for (int j = 0; j < joint_count; ++j) next[v][j] /= sum;
    }
    weights.swap(next);
  }
  out.skin.joints.resize(n);
  out.skin.weights.resize(n);
  std::vector<int> order(joint_count);
  for (int v = 0; v < n; ++v) {
    for (int j = 0; j < joint_count; ++j) order[j] = j;
    std::partial_sort(order.begin(), order.begin() + kMaxInfluences, order.end(),
                      [&](int a, int b) { return weights[v][a] > weights[v][b]; });
    float sum = 0;
    for (int i = 0; i < kMaxInfluences; ++i) sum += weights[v][order[i]];
    for (int i = 0; i < kMaxInfluences; ++i) {
      out.skin.joints[v][i] = static_cast<uint16_t>(order[i]);
      out.skin.weights[v][i] = weights[v][order[i]] / sum;
    }
  }
  out.rest = std::move(mesh);
  out.validate();
  return out;
}

int bodyDetailVertices(BodyDetail detail) {
  return detail == BodyDetail::kFine ? 4000 : 2000;
}

const char* bodyDetailName(BodyDetail detail) {
  return detail == BodyDetail::kFine ? "fine" : "standard";
}

BodyDetail parseBodyDetail(const std::string& name) {
  if (name == "standard") return BodyDetail::kStandard;
  if (name == "fine") return BodyDetail::kFine;
  throw Error("body '" + name + "': standard or fine expected");
}

SkinnedMesh loadGenericHuman(BodyDetail detail) {
  const std::filesystem::path path = resourcePath(
      detail == BodyDetail::kFine ? "body/generic_human_fine.glb" : "body/generic_human.glb");
  SkinnedMesh mesh = loadSkinnedMesh(path);
  try {
    checkHumanJointOrder(mesh.skeleton, path.string());
  } catch (const std::invalid_argument& e) {
    throw Error(e.what());
  }
  return mesh;
}

std::string bodyChoiceName(const BodyChoice& choice) {
  return choice.file.empty() ? bodyDetailName(choice.detail) : choice.file.string();
}

BodyChoice parseBodyChoice(const std::string& text) {
  if (text == "standard" || text == "fine") return {parseBodyDetail(text), {}};
  std::error_code ec;
  if (text.empty() || !std::filesystem::is_regular_file(text, ec)) {
    throw Error(
        fmt::format("{} is neither standard nor fine nor a file: expected standard, fine "
                    "or a rigged human's file (glTF/GLB, FBX, DAE, X)",
                    quotedInput(text)));
  }
  return {BodyDetail::kStandard, text};
}

SkinnedMesh loadBody(const BodyChoice& choice) {
  return choice.file.empty() ? loadGenericHuman(choice.detail) : loadHumanBody(choice.file);
}

Status readApart(const std::string& file, const std::function<void()>& read) {
  const Status read_apart = runInChildProcess(read);
  if (read_apart.ok()) return {};
  const std::string& error = read_apart.error();
  if (error.rfind("crashed (", 0) == 0)
    return Status::failure(fmt::format(
        "{}: the import crashed inside the mesh library ({}): a damaged or hostile file, or one "
        "nested too deep",
        file, error.substr(9, error.size() - 10)));
  return Status::failure(error == "failed" ? file + ": the import failed" : error);
}

Status checkBodyFile(const std::filesystem::path& file) {
  return readApart(file.string(), [&] { loadBody(BodyChoice{BodyDetail::kStandard, file}); });
}

SkinnedMesh trackingModelFor(const SkinnedMesh& body) {
  static const Skeleton generic = makeHumanSkeleton();
  bool same = body.skeleton.jointCount() == generic.jointCount();
  for (int j = 0; same && j < generic.jointCount(); ++j) {
    same = body.skeleton.joint(j).name == generic.joint(j).name &&
           (body.skeleton.restPositions()[j] - generic.restPositions()[j]).norm() < 1e-3;
  }
  return same ? body : loadGenericHuman();
}

}  // namespace lumistage
