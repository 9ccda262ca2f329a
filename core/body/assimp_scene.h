#pragma once

// The pieces of an Assimp scene that glTF (mesh_io.cpp) and FBX (fbx_export.cpp) writing share:
// the skeleton's nodes and the skinned mesh, in the file's axes and units.
#include <assimp/scene.h>

#include <Eigen/Core>
#include <vector>

#include "core/body/skinned_mesh.h"

namespace lumistage {

aiVector3D toAi(const Eigen::Vector3d& v);
// A node transform or bone offset that only translates.
aiMatrix4x4 aiTranslation(const Eigen::Vector3d& t);

// The joint nodes, joint 0's parent `root` (which does not list it: the caller does), each node's
// rest transform a translation (our rest frames are world aligned). `c` turns our axes into the
// file's, `s` scales metres into its unit.
std::vector<aiNode*> skeletonNodes(const Skeleton& skeleton, const Eigen::Matrix3d& c, double s,
                                   aiNode* root);

// The rest mesh, named `name`, with one bone per joint (its offset matrix undoes the joint's rest
// position) holding the vertices' skin weights. Material 0.
aiMesh* skinnedAiMesh(const SkinnedMesh& body, const char* name, const Eigen::Matrix3d& c,
                      double s);

}  // namespace lumistage
