#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/body/human_skeleton.h"
#include "core/body/skinned_mesh.h"

namespace lumistage {

// A rigged human from a file (any skeleton, any bind pose) made into one the pipeline poses with
// the human skeleton (human_skeleton.h): our 24 joints in their order, world-aligned rest frames,
// the T-pose at rest.

// How one of our joints was found among the file's.
enum class JointFound {
  kName,       // its name says which joint it is (humanJointNameFor, Rigify/metarig names)
  kNameChain,  // its name says the limb and side ("leg_joint_R_2"), its place in the chain which
  kGeometry,   // the bone chains by position: legs down from the pelvis, arms sideways
  kPlaced,     // none of the file's: placed between (or beyond) its mapped neighbours
};
const char* jointFoundName(JointFound how);

struct BodyMapping {
  // Per joint of ours (HumanJoint order): the file joint it is, -1 for a placed one.
  std::vector<int> file_joint;
  std::vector<JointFound> how;
  // Per file joint: our joint its skin weights go to (the joint it is, or its nearest mapped
  // ancestor's; the pelvis for joints above the pelvis).
  std::vector<int> weights_to;
};

// Maps a file's skeleton (rest positions in our axes, metres; mesh_io.h) onto ours: by name where
// the names tell, by the bone chains' geometry for the rest. Throws Error naming `source`: no two
// legs (feet at the bottom on either side of the body), no arms, no head above them, a leg or arm
// chain of fewer than three joints, or names that contradict the hierarchy (an elbow that is not
// below its shoulder).
BodyMapping mapHumanJoints(const Skeleton& file_skeleton, std::string_view source);

// One line per joint of ours: "  left_knee      <- leg_joint_L_2 (name and chain order)", then the
// file joints that map to none of ours and where their weights go.
std::string describeBodyMapping(const BodyMapping& mapping, const Skeleton& file_skeleton);

// The file's body on the human skeleton: our rest joints where the file's are (placed ones between
// their neighbours), the mesh re-posed by linear blend skinning so that every mapped bone points
// as ours does at rest (arms level to the sides, legs straight down), skin weights moved to our
// joints (at most four, renormalised), normals recomputed, standing on z = 0. Joint limits are the
// human skeleton's. A mesh that is not closed gets a warning (refinement and rendering see through
// its holes); a vertex in no triangle gets the direction from its joint as its normal.
SkinnedMesh fitToHumanSkeleton(const SkinnedMesh& file_body, const BodyMapping& mapping,
                               std::string_view source);

// loadSkinnedMesh, mapHumanJoints and fitToHumanSkeleton; the mapping too, when asked for.
SkinnedMesh loadHumanBody(const std::filesystem::path& path, BodyMapping* mapping = nullptr);

}  // namespace lumistage
