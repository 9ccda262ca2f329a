#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "core/base/status.h"
#include "core/body/human_skeleton.h"
#include "core/body/skinned_mesh.h"

namespace lumistage {

// Surface materials of a human model, stored per vertex in SkinnedMesh::materials.
enum class Material : uint8_t { kSkin = 0, kShirt = 1, kTrousers = 2, kHair = 3, kShoes = 4 };

struct HumanModelSpec {
  BodyShape shape;
  // Clothing-like volume over the body: a loose shirt with short sleeves, trousers flaring at the
  // ankles, hair and shoes. Off for the generic human, on for the virtual studio's actor.
  bool clothing = false;
  // The mesh is resized toward this many vertices (surface nets over a grid whose cell is
  // chosen for it); the result lands within a few percent.
  int target_vertices = 2000;
};

// A closed, manifold human mesh in the T-pose, generated from a smooth union of tapered capsules
// and ellipsoids around the bones of makeHumanSkeleton(spec.shape), with smooth skinning weights
// (nearest bones, limited to a bone's neighbours so that legs never pull on each other, then
// smoothed over the mesh) and per-vertex materials. Deterministic.
SkinnedMesh makeHumanModel(const HumanModelSpec& spec = {});

// How finely the shipped generic human is tessellated. The studio and every node must pose the
// same one (a node told offsets for another says so and leaves them unused).
//   kStandard, about 2000 vertices: four nodes and the studio sharing one PC refine and render it
//     at video rate;
//   kFine, about 4000: for nodes on PCs of their own (the reference rig's). Views left out score
//     0.2 dB higher over the actor's mask and 0.65 dB as the studio shows them (docs/lumigraph.md),
//     for twice the nodes' refinement and render work and twice the studio's refinement module.
enum class BodyDetail { kStandard, kFine };
// makeHumanModel's target_vertices for each.
int bodyDetailVertices(BodyDetail detail);
// "standard", "fine"; parseBodyDetail throws Error naming what it expected.
const char* bodyDetailName(BodyDetail detail);
BodyDetail parseBodyDetail(const std::string& name);

// The generic human as shipped: resources/body/generic_human.glb (generic_human_fine.glb for
// kFine), written once by `lumistage body generate [--vertices 4000]` (makeHumanModel with the
// defaults but bodyDetailVertices) and read from there at run time, so that a studio can replace
// it with any rigged mesh. Throws Error when the file is missing or malformed.
SkinnedMesh loadGenericHuman(BodyDetail detail = BodyDetail::kStandard);

// The body a stage poses: the generic human at a detail, or the actor's own rigged human from a
// file (any format Assimp reads), mapped onto the human skeleton (body_mapping.h).
struct BodyChoice {
  BodyDetail detail = BodyDetail::kStandard;
  std::filesystem::path file;  // empty: the generic human
  bool operator==(const BodyChoice&) const = default;
};
// "standard", "fine", or a file's path (as given).
std::string bodyChoiceName(const BodyChoice& choice);
// "standard" and "fine" are the generic human; anything else is a file, which must exist (throws
// Error naming it otherwise).
BodyChoice parseBodyChoice(const std::string& text);
// loadGenericHuman, or loadHumanBody for a file.
SkinnedMesh loadBody(const BodyChoice& choice);
// Runs `read` (reading `file` through the mesh library) in a child process (runInChildProcess):
// ok when it read it; failed with its own error, or, when it crashed, saying so naming the file
// ("FILE: the import crashed inside the mesh library (SIGNAL): ..."). A file nested too deep for
// Assimp costs the child, not the caller.
Status readApart(const std::string& file, const std::function<void()>& read);
// readApart of loadBody on the file: whether --body FILE can pose it.
Status checkBodyFile(const std::filesystem::path& file);

// The mesh the tracker builds its capsules from when the nodes pose `body`: the body itself when
// it stands on the generic human's skeleton (its joints within a millimetre of
// makeHumanSkeleton()'s: either generic human, makeHumanModel's default shape), else the standard
// generic human. The tracker calibrates the generic human's proportions to the actor
// (makeHumanSkeleton(BodyShape)); a body of other proportions hung on them misplaces its capsules
// (CesiumMan, whose head stands a third of a metre tall: 24 of 60 frames tracked, 189 mm MPJPE on
// the reference walk).
SkinnedMesh trackingModelFor(const SkinnedMesh& body);

}  // namespace lumistage
