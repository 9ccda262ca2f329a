#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/capture/image_files.h"
#include "core/geometry/rig.h"

namespace lumistage {

// The parts of a take: the folders holding session.yaml among `paths`, where a path without one
// stands for its sub-folders that hold one (a take folder with a part per node). Sorted by path.
// Throws Error naming a path that is neither.
std::vector<std::filesystem::path> takeParts(const std::vector<std::filesystem::path>& paths);

struct TakeMergeReport {
  int frames = 0;                  // frame sets in the merged session
  std::vector<std::string> notes;  // per part: the frames it had that others lacked
  int64_t bytes = 0;               // image bytes written
};

// Joins the parts of a take that the camera nodes recorded (each a session of its own cameras,
// core/pipeline/take_recorder.h) into one session of every camera at `out`
// (docs/session-format.md): the frames whose id every node's parts hold, timestamps from the
// first node's. Parts of the same cameras are one node's (<node>, then <node>-2... after a
// restart during the take): their frames are joined, a continuation's timestamps moved to follow
// on at the session's rate. Cameras and nodes in the order of `rig` when given (its cameras must be
// exactly the parts'), else part after part. The images are copied as they are, or, with `files`
// other than the parts' (a take recorded as PNM, kept as PNG), decoded and written in those.
// `progress(done, total)` after each frame. The session is written as `out`.partial and renamed
// to `out` once whole: a merge that fails (a full disk) leaves nothing under the name, and removes
// what it wrote (the parts are untouched). Throws Error naming the part and the reason: parts of
// different pixel formats or rates, a camera in two parts, no frame in common, `out` not empty.
TakeMergeReport mergeTake(const std::vector<std::filesystem::path>& parts,
                          const std::filesystem::path& out, const std::optional<Rig>& rig = {},
                          std::optional<ImageFiles> files = {},
                          const std::function<void(int, int)>& progress = {});

}  // namespace lumistage
