#include "core/body/assimp_scene.h"

#include <algorithm>

namespace lumistage {

aiVector3D toAi(const Eigen::Vector3d& v) {
  return {float(v.x()), float(v.y()), float(v.z())};
}

aiMatrix4x4 aiTranslation(const Eigen::Vector3d& t) {
  aiMatrix4x4 m;  // identity
  m.a4 = float(t.x());
  m.b4 = float(t.y());
  m.c4 = float(t.z());
  return m;
}

std::vector<aiNode*> skeletonNodes(const Skeleton& skeleton, const Eigen::Matrix3d& c, double s,
                                   aiNode* root) {
  const int n = skeleton.jointCount();
  std::vector<aiNode*> nodes(n);
  std::vector<std::vector<int>> children(n);
  for (int j = 1; j < n; ++j) children[skeleton.joint(j).parent].push_back(j);
  for (int j = 0; j < n; ++j) {
    nodes[j] = new aiNode(skeleton.joint(j).name);
    nodes[j]->mTransformation = aiTranslation(s * (c * skeleton.joint(j).offset_m));
  }
  for (int j = 0; j < n; ++j) {
    nodes[j]->mParent = j == 0 ? root : nodes[skeleton.joint(j).parent];
    if (children[j].empty()) continue;
    nodes[j]->mNumChildren = unsigned(children[j].size());
    nodes[j]->mChildren = new aiNode*[children[j].size()];
    for (size_t k = 0; k < children[j].size(); ++k) nodes[j]->mChildren[k] = nodes[children[j][k]];
  }
  return nodes;
}

aiMesh* skinnedAiMesh(const SkinnedMesh& body, const char* name, const Eigen::Matrix3d& c,
                      double s) {
  auto* m = new aiMesh;
  m->mName = name;
  m->mMaterialIndex = 0;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const int n = body.rest.vertexCount();
  m->mNumVertices = unsigned(n);
  m->mVertices = new aiVector3D[n];
  m->mNormals = new aiVector3D[n];
  for (int v = 0; v < n; ++v) {
    m->mVertices[v] = toAi(s * (c * body.rest.positions.col(v).cast<double>()));
    m->mNormals[v] = toAi(c * body.rest.normals.col(v).cast<double>());
  }
  m->mNumFaces = unsigned(body.rest.triangles.size());
  m->mFaces = new aiFace[m->mNumFaces];
  for (size_t t = 0; t < body.rest.triangles.size(); ++t) {
    m->mFaces[t].mNumIndices = 3;
    m->mFaces[t].mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) m->mFaces[t].mIndices[k] = unsigned(body.rest.triangles[t][k]);
  }
  const Skeleton& skeleton = body.skeleton;
  std::vector<std::vector<aiVertexWeight>> weights(skeleton.jointCount());
  for (int v = 0; v < n; ++v) {
    for (int k = 0; k < kMaxInfluences; ++k) {
      if (body.skin.weights[v][k] > 0)
        weights[body.skin.joints[v][k]].emplace_back(unsigned(v), body.skin.weights[v][k]);
    }
  }
  m->mNumBones = unsigned(skeleton.jointCount());
  m->mBones = new aiBone*[m->mNumBones];
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    auto* bone = new aiBone;
    bone->mName = skeleton.joint(j).name;
    bone->mOffsetMatrix = aiTranslation(-s * (c * skeleton.restPositions()[j]));
    bone->mNumWeights = unsigned(weights[j].size());
    bone->mWeights = new aiVertexWeight[std::max<size_t>(weights[j].size(), 1)];
    std::copy(weights[j].begin(), weights[j].end(), bone->mWeights);
    m->mBones[j] = bone;
  }
  return m;
}

}  // namespace lumistage
