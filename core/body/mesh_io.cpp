#include "core/body/mesh_io.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "core/base/error.h"
#include "core/body/assimp_scene.h"
#include "core/body/bvh.h"
#include "core/body/gltf_check.h"
#include "core/body/human_skeleton.h"
#include "core/body/mesh_axes.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

constexpr const char* kMaterialsName = "lumistage_vertex_materials";

Eigen::Affine3f toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4f e;
  e << m.a1, m.a2, m.a3, m.a4,  //
      m.b1, m.b2, m.b3, m.b4,   //
      m.c1, m.c2, m.c3, m.c4,   //
      m.d1, m.d2, m.d3, m.d4;
  return Eigen::Affine3f(e);
}

std::unique_ptr<aiScene> buildScene(const SkinnedMesh& mesh) {
  const Eigen::Matrix3d c = yUpToOurs();  // its own inverse: ours to the file's too
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode("lumistage_actor");
  const std::vector<aiNode*> nodes = skeletonNodes(mesh.skeleton, c, 1.0, scene->mRootNode);
  scene->mRootNode->mNumChildren = 1;
  scene->mRootNode->mChildren = new aiNode* [1] { nodes[0] };
  scene->mRootNode->mNumMeshes = 1;
  scene->mRootNode->mMeshes = new unsigned[1]{0};

  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial* [1] { new aiMaterial };
  const aiString material_name(mesh.materials.empty() ? "lumistage_skin" : kMaterialsName);
  scene->mMaterials[0]->AddProperty(&material_name, AI_MATKEY_NAME);

  aiMesh* m = skinnedAiMesh(mesh, "actor", c, 1.0);
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh* [1] { m };
  if (!mesh.materials.empty()) {
    // Material indices ride in texture coordinate set 0, u = index (exact in a float), v = 0.
    const int n = mesh.rest.vertexCount();
    m->mTextureCoords[0] = new aiVector3D[n];
    m->mNumUVComponents[0] = 2;
    for (int v = 0; v < n; ++v) m->mTextureCoords[0][v] = aiVector3D(mesh.materials[v], 0, 0);
  }
  return scene;
}

void exportScene(const aiScene& scene, const char* format, const fs::path& target,
                 const fs::path& file) {
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, file.string()) != AI_SUCCESS) {
    throw Error(
        fmt::format("{}: glTF export failed: {}", target.string(), exporter.GetErrorString()));
  }
}

// Rejects a file Assimp can read but we cannot use.
[[noreturn]] void fail(const fs::path& path, const std::string& message) {
  throw Error(path.string() + ": " + message);
}

const aiNode* nodeOfMesh(const aiNode* node, unsigned mesh) {
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    if (node->mMeshes[k] == mesh) return node;
  }
  for (unsigned k = 0; k < node->mNumChildren; ++k) {
    if (const aiNode* found = nodeOfMesh(node->mChildren[k], mesh)) return found;
  }
  return nullptr;
}

Eigen::Affine3f globalTransform(const aiNode* node) {
  Eigen::Affine3f t = Eigen::Affine3f::Identity();
  for (; node != nullptr; node = node->mParent) t = toEigen(node->mTransformation) * t;
  return t;
}

bool isAncestorOrSelf(const aiNode* ancestor, const aiNode* node) {
  for (; node != nullptr; node = node->mParent) {
    if (node == ancestor) return true;
  }
  return false;
}

const aiNode* commonAncestor(const aiNode* a, const aiNode* b) {
  for (; a != nullptr; a = a->mParent) {
    if (isAncestorOrSelf(a, b)) return a;
  }
  return nullptr;
}

JointLimits importedLimits(const std::string& name, const Skeleton& human) {
  std::optional<int> j = human.findJoint(name);
  if (!j) {
    if (auto ours = humanJointNameFor(name)) j = human.findJoint(*ours);
  }
  if (j) return human.joint(*j).limits;
  constexpr double kPi = std::numbers::pi;
  return {Eigen::Vector3d::Constant(-kPi), Eigen::Vector3d::Constant(kPi)};
}

// Vertices with more than four positive bone weights, and the most on one vertex, over the
// triangle meshes `meshes`. Throws Error naming the file for a weight on a vertex the mesh has not.
struct InfluenceCount {
  int crowded = 0;
  size_t most = 0;
};

InfluenceCount countInfluences(const aiScene& scene, const std::vector<unsigned>& meshes,
                               const fs::path& path) {
  InfluenceCount out;
  std::vector<size_t> count;
  for (unsigned i : meshes) {
    const aiMesh* m = scene.mMeshes[i];
    count.assign(m->mNumVertices, 0);
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiBone* bone = m->mBones[b];
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& vw = bone->mWeights[w];
        if (vw.mVertexId >= m->mNumVertices) {
          fail(path,
               fmt::format("bone '{}' weights vertex {} of mesh '{}', which has {}",
                           bone->mName.C_Str(), vw.mVertexId, m->mName.C_Str(), m->mNumVertices));
        }
        if (vw.mWeight > 0) ++count[vw.mVertexId];
      }
    }
    for (size_t c : count) {
      if (c > kMaxInfluences) ++out.crowded;
      out.most = std::max(out.most, c);
    }
  }
  return out;
}

// The file read by Assimp (through `importer`, which owns the scene), with a scene graph.
const aiScene* readScene(Assimp::Importer& importer, const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    fail(path, "no such file (or not a regular file), expected a mesh file");
  // Assimp recurses per level of a glTF's JSON and nodes: too deep a file is refused before it.
  checkGltfNesting(path);
  // FBX pivots would otherwise become helper nodes ("Hips_$AssimpFbx$_Rotation") between bones,
  // and so joints of ours.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  // For aiProcess_LimitBoneWeights, applied later once the skeleton is known.
  importer.SetPropertyInteger(AI_CONFIG_PP_LBW_MAX_WEIGHTS, kMaxInfluences);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_JoinIdenticalVertices | aiProcess_Triangulate |
                                           aiProcess_GenSmoothNormals | aiProcess_SortByPType);
  if (scene == nullptr) {
    // Assimp's reason may quote the rest of the file: shown shortened and escaped.
    fail(path, std::string("cannot read it as a mesh (unreadable or unsupported format): ") +
                   printableInput(importer.GetErrorString(), 300));
  }
  if (scene->mRootNode == nullptr) fail(path, "no scene graph, expected a rigged mesh");
  return scene;
}

// The steps after reading walk the scene graph recursively: its depth is checked first, without
// recursion (formats other than glTF are not checked before Assimp).
void checkNodeDepth(const aiScene& scene, const fs::path& path) {
  constexpr int kMaxDepth = GltfNestingLimits{}.node_depth;
  std::vector<std::pair<const aiNode*, int>> stack{{scene.mRootNode, 1}};
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    if (depth > kMaxDepth)
      fail(path, fmt::format("its nodes nest deeper than {} levels (node {})", kMaxDepth,
                             quotedInput(node->mName.C_Str(), 64)));
    for (unsigned k = 0; k < node->mNumChildren; ++k)
      stack.emplace_back(node->mChildren[k], depth + 1);
  }
}

// The triangle meshes (SortByPType moved points and lines into meshes of their own).
std::vector<unsigned> triangleMeshes(const aiScene& scene, const fs::path& path) {
  std::vector<unsigned> meshes;
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    if (scene.mMeshes[i]->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) meshes.push_back(i);
  }
  if (meshes.empty()) fail(path, "no mesh, expected a triangle mesh bound to a skeleton");
  return meshes;
}

// The skeleton: bone nodes and their ancestors up to the lowest common one.
struct SceneSkeleton {
  const aiNode* root = nullptr;
  std::set<const aiNode*> nodes;
};

SceneSkeleton findSkeleton(const aiScene& scene, const std::vector<unsigned>& meshes,
                           const fs::path& path) {
  SceneSkeleton out;
  std::vector<const aiNode*> mesh_roots(scene.mNumMeshes, nullptr);
  std::set<const aiNode*> bone_nodes;
  for (unsigned i : meshes) {
    const aiMesh* m = scene.mMeshes[i];
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiNode* node = scene.mRootNode->FindNode(m->mBones[b]->mName);
      if (node == nullptr) {
        fail(path, fmt::format("bone '{}' of mesh '{}' has no node in the scene graph",
                               m->mBones[b]->mName.C_Str(), m->mName.C_Str()));
      }
      bone_nodes.insert(node);
      mesh_roots[i] = mesh_roots[i] ? commonAncestor(mesh_roots[i], node) : node;
    }
    if (mesh_roots[i] == nullptr) continue;
    for (unsigned k : meshes) {
      if (k >= i || mesh_roots[k] == nullptr) continue;
      if (!isAncestorOrSelf(mesh_roots[k], mesh_roots[i]) &&
          !isAncestorOrSelf(mesh_roots[i], mesh_roots[k])) {
        fail(path, fmt::format("meshes '{}' and '{}' are bound to different skeletons (rooted at "
                               "'{}' and '{}'), expected one skeleton",
                               scene.mMeshes[k]->mName.C_Str(), m->mName.C_Str(),
                               mesh_roots[k]->mName.C_Str(), mesh_roots[i]->mName.C_Str()));
      }
    }
    out.root = out.root ? commonAncestor(out.root, mesh_roots[i]) : mesh_roots[i];
  }
  if (out.root == nullptr) {
    fail(path, "no skeleton: the mesh has no bones, expected a mesh rigged to a skeleton");
  }
  for (const aiNode* node : bone_nodes) {
    for (; node != out.root; node = node->mParent) out.nodes.insert(node);
  }
  out.nodes.insert(out.root);
  return out;
}

// World bind positions: a bone's from its offset matrix (in its mesh's space, then through the
// mesh node), another joint's from its node. Rotated bind frames keep only their positions:
// our rest frames are world aligned.
std::map<const aiNode*, Eigen::Vector3f> bindPositions(const aiScene& scene,
                                                       const std::vector<unsigned>& meshes) {
  std::map<const aiNode*, Eigen::Vector3f> bind_position;
  for (unsigned i : meshes) {
    const aiMesh* m = scene.mMeshes[i];
    const aiNode* mesh_node = nodeOfMesh(scene.mRootNode, i);
    const Eigen::Affine3f mesh_global =
        mesh_node ? globalTransform(mesh_node) : Eigen::Affine3f::Identity();
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiNode* node = scene.mRootNode->FindNode(m->mBones[b]->mName);
      if (bind_position.count(node)) continue;
      const Eigen::Affine3f offset = toEigen(m->mBones[b]->mOffsetMatrix);
      bind_position[node] = mesh_global * offset.inverse().translation();
    }
  }
  return bind_position;
}

// The skeleton's joints in our coordinates, each node's joint, and the map from the scene's
// coordinates to ours.
struct ImportedJoints {
  std::vector<Joint> joints;
  std::map<const aiNode*, int> joint_of;
  Eigen::Matrix3f c;
};

// The joints in the scene's coordinates, parents first; then the file's axes and units (and,
// where its format cannot tell, its skeleton) decide the map to ours.
ImportedJoints importJoints(const aiScene& scene, const std::vector<unsigned>& meshes,
                            const SceneSkeleton& skeleton, const fs::path& path) {
  const std::map<const aiNode*, Eigen::Vector3f> bind_position = bindPositions(scene, meshes);
  ImportedJoints out;
  std::vector<std::string> names;
  std::vector<int> parents;
  std::vector<Eigen::Vector3f> scene_positions;
  auto addJoints = [&](auto&& self, const aiNode* node, int parent) -> void {
    if (!skeleton.nodes.count(node)) return;
    const auto it = bind_position.find(node);
    const int index = static_cast<int>(names.size());
    out.joint_of[node] = index;
    names.emplace_back(node->mName.C_Str());
    parents.push_back(parent);
    scene_positions.push_back(it != bind_position.end() ? it->second
                                                        : globalTransform(node).translation());
    for (unsigned k = 0; k < node->mNumChildren; ++k) self(self, node->mChildren[k], index);
  };
  addJoints(addJoints, skeleton.root, -1);
  out.c = sceneToOurs(scene, path, skeletonAxes(names, scene_positions));
  const Skeleton human = makeHumanSkeleton();
  for (size_t j = 0; j < names.size(); ++j) {
    const Eigen::Vector3f p = out.c * scene_positions[j];
    const Eigen::Vector3f offset =
        parents[j] < 0 ? p : Eigen::Vector3f(p - out.c * scene_positions[parents[j]]);
    out.joints.push_back(
        {names[j], parents[j], offset.cast<double>(), importedLimits(names[j], human)});
  }
  return out;
}

// Mesh m's per-vertex materials into out.materials from `base` on, when its material says it
// carries them (kMaterialsName); whether it does.
bool readMaterials(const aiScene& scene, const aiMesh& m, size_t base, size_t total,
                   const fs::path& path, SkinnedMesh& out) {
  aiString material_name;
  const bool has_materials =
      m.mMaterialIndex < scene.mNumMaterials &&
      scene.mMaterials[m.mMaterialIndex]->Get(AI_MATKEY_NAME, material_name) == AI_SUCCESS &&
      std::string(material_name.C_Str()) == kMaterialsName;
  if (!has_materials) return false;
  if (m.mTextureCoords[0] == nullptr) {
    fail(path, fmt::format("mesh '{}' has material '{}' but no texture coordinates, expected "
                           "material indices in set 0",
                           m.mName.C_Str(), kMaterialsName));
  }
  out.materials.resize(total);
  for (unsigned v = 0; v < m.mNumVertices; ++v) {
    const float u = m.mTextureCoords[0][v].x;
    if (!(u >= 0 && u <= 255 && u == std::round(u))) {
      fail(path, fmt::format("mesh '{}' vertex {}: material index {} is not a whole number "
                             "from 0 to 255",
                             m.mName.C_Str(), v, u));
    }
    out.materials[base + v] = static_cast<uint8_t>(u);
  }
  return true;
}

// Each vertex's bone influences: (joint, weight) pairs.
using Influences = std::vector<std::vector<std::pair<int, float>>>;

// Vertices, triangles and weights of every mesh, merged: the rest surface and the materials into
// `out`, the vertices' influences returned.
Influences readGeometry(const aiScene& scene, const std::vector<unsigned>& meshes,
                        const ImportedJoints& imported, const fs::path& path, SkinnedMesh& out) {
  const Eigen::Matrix3f& c = imported.c;
  const bool mirrored = c.determinant() < 0;
  size_t total = 0;
  for (unsigned i : meshes) total += scene.mMeshes[i]->mNumVertices;
  if (total == 0) fail(path, "its meshes have no vertices, expected a triangle mesh");
  out.rest.positions.resize(3, static_cast<Eigen::Index>(total));
  out.rest.normals.resize(3, static_cast<Eigen::Index>(total));
  Influences influences(total);
  int material_meshes = 0;
  size_t base = 0;
  for (unsigned i : meshes) {
    const aiMesh* m = scene.mMeshes[i];
    const aiNode* mesh_node = nodeOfMesh(scene.mRootNode, i);
    const Eigen::Affine3f mesh_global =
        mesh_node ? globalTransform(mesh_node) : Eigen::Affine3f::Identity();
    const Eigen::Matrix3f normal_matrix = mesh_global.linear().inverse().transpose();
    if (m->mNormals == nullptr)
      fail(path, "mesh '" + std::string(m->mName.C_Str()) + "' has no normals");
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const Eigen::Vector3f p(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z);
      const Eigen::Vector3f n(m->mNormals[v].x, m->mNormals[v].y, m->mNormals[v].z);
      out.rest.positions.col(base + v) = c * (mesh_global * p);
      out.rest.normals.col(base + v) = (c * (normal_matrix * n)).normalized();
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines of a mixed mesh
      // A mirror (a left-handed file) turns the winding: swap two corners back.
      const int b = mirrored ? 2 : 1;
      out.rest.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[b],
                                      base + face.mIndices[3 - b]);
    }
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiBone* bone = m->mBones[b];
      const int joint = imported.joint_of.at(scene.mRootNode->FindNode(bone->mName));
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& vw = bone->mWeights[w];  // indices checked by countInfluences
        if (vw.mWeight > 0) influences[base + vw.mVertexId].emplace_back(joint, vw.mWeight);
      }
    }
    if (readMaterials(scene, *m, base, total, path, out)) ++material_meshes;
    base += m->mNumVertices;
  }
  if (material_meshes != 0 && material_meshes != static_cast<int>(meshes.size())) {
    fail(path, fmt::format("{} of {} meshes carry per-vertex materials, expected all or none",
                           material_meshes, meshes.size()));
  }
  return influences;
}

// Weights: each vertex weighted, at most four (the largest) kept, normalised to sum 1.
void setWeights(Influences& influences, const InfluenceCount& crowding, const fs::path& path,
                SkinnedMesh& out) {
  const size_t total = influences.size();
  const int unweighted = static_cast<int>(
      std::count_if(influences.begin(), influences.end(), [](const auto& l) { return l.empty(); }));
  if (unweighted > 0) {
    fail(path, fmt::format("{} of {} vertices have no bone weights, expected every vertex bound to "
                           "the skeleton",
                           unweighted, total));
  }
  if (crowding.crowded > 0) {
    spdlog::warn(
        "{}: {} of {} vertices have more than {} bone influences (up to {}): keeping the "
        "{} largest of each, renormalised",
        path.string(), crowding.crowded, total, kMaxInfluences, crowding.most, kMaxInfluences);
  }
  out.skin.joints.assign(total, {0, 0, 0, 0});
  out.skin.weights.assign(total, {0, 0, 0, 0});
  for (size_t v = 0; v < total; ++v) {
    auto& list = influences[v];
    if (list.size() > kMaxInfluences) {  // Assimp's step has done this; here it is certain
      std::partial_sort(list.begin(), list.begin() + kMaxInfluences, list.end(),
                        [](const auto& a, const auto& b) { return a.second > b.second; });
      list.resize(kMaxInfluences);
    }
    float sum = 0;
    for (const auto& [joint, weight] : list) sum += weight;
    for (size_t k = 0; k < list.size(); ++k) {
      out.skin.joints[v][k] = static_cast<uint16_t>(list[k].first);
      out.skin.weights[v][k] = list[k].second / sum;
    }
  }
}

// The mesh validated, and its height checked.
void checkMesh(const SkinnedMesh& out, const fs::path& path) {
  try {
    out.validate();
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("unusable mesh: ") + e.what());
  }
  // A human's height tells whether the units were right where the file gave none (or wrong ones).
  const float height = out.rest.positions.row(2).maxCoeff() - out.rest.positions.row(2).minCoeff();
  if (!(height >= 0.2f && height <= 3.0f)) {
    spdlog::warn(
        "{}: the body stands {:.3g} m tall as read, expected 0.2 to 3 m: are its units "
        "(or the file's unit scale) right?",
        path.string(), height);
  }
}

}  // namespace

void saveSkinnedMeshGltf(const SkinnedMesh& mesh, const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext != ".glb" && ext != ".gltf") {
    fail(path, fmt::format("unknown extension '{}', expected .glb or .gltf", ext));
  }
  try {
    mesh.validate();
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("cannot write an invalid mesh: ") + e.what());
  }
  if (mesh.skeleton.jointCount() == 0) fail(path, "cannot write a mesh without a skeleton");
  const std::unique_ptr<aiScene> scene = buildScene(mesh);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;

  if (ext == ".glb") {
    // One file: export beside the target, then rename over it.
    std::string temp = path.string() + ".tmp-XXXXXX";
    const int fd = ::mkstemp(temp.data());
    if (fd < 0) fail(path, "cannot create a temporary file beside it");
    ::close(fd);
    // mkstemp makes it private; a mesh file is for everyone to read, like writeFileAtomically's.
    fs::permissions(temp,
                    fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                        fs::perms::others_read,
                    ec);
    try {
      exportScene(*scene, "glb2", path, temp);
    } catch (...) {
      fs::remove(temp, ec);
      throw;
    }
    fs::rename(temp, path, ec);
    if (ec) {
      fs::remove(temp, ec);
      fail(path, "rename into place failed: " + ec.message());
    }
    return;
  }

  // .gltf: the exporter also writes a .bin buffer and names it after the file, so export into a
  // temporary folder under the final name, then move the buffers in first and the .gltf last:
  // a reader never finds a .gltf whose buffer is missing.
  std::string temp_dir = (dir / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
  if (::mkdtemp(temp_dir.data()) == nullptr) {
    fail(path, "cannot create a temporary folder beside it");
  }
  auto cleanup = [&] { fs::remove_all(temp_dir, ec); };
  try {
    exportScene(*scene, "gltf2", path, fs::path(temp_dir) / path.filename());
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(temp_dir)) files.push_back(entry.path());
    std::stable_partition(files.begin(), files.end(),
                          [&](const fs::path& p) { return p.filename() != path.filename(); });
    for (const fs::path& file : files) {
      fs::rename(file, dir / file.filename(), ec);
      if (ec)
        fail(path, "rename of " + file.filename().string() + " into place failed: " + ec.message());
    }
  } catch (...) {
    cleanup();
    throw;
  }
  cleanup();
}

SkinnedMesh loadSkinnedMesh(const fs::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = readScene(importer, path);
  checkNodeDepth(*scene, path);
  const std::vector<unsigned> meshes = triangleMeshes(*scene, path);
  const SceneSkeleton skeleton = findSkeleton(*scene, meshes, path);
  ImportedJoints imported = importJoints(*scene, meshes, skeleton, path);

  // More than four influences on a vertex: Assimp keeps the four largest and renormalises them.
  // Counted (and vertex indices checked) before, as the step drops what it does not keep, bones
  // left without weights included: the skeleton above was taken from all of them.
  const InfluenceCount crowding = countInfluences(*scene, meshes, path);
  if (crowding.most > static_cast<size_t>(kMaxInfluences)) {
    scene = importer.ApplyPostProcessing(aiProcess_LimitBoneWeights);
    if (scene == nullptr) {
      fail(path,
           std::string("limiting bone influences to four failed: ") + importer.GetErrorString());
    }
  }

  SkinnedMesh out;
  try {
    out.skeleton = Skeleton(std::move(imported.joints));
  } catch (const std::invalid_argument& e) {
    fail(path, std::string("unusable skeleton: ") + e.what());
  }
  Influences influences = readGeometry(*scene, meshes, imported, path, out);
  setWeights(influences, crowding, path, out);
  checkMesh(out, path);
  return out;
}

}  // namespace lumistage
