#pragma once

#include <memory>
#include <vector>

#include "core/capture/image.h"
#include "core/capture/session_reader.h"
#include "core/imaging/keyer.h"

namespace lumistage {

// A camera's clean plate (BackgroundModel) learnt from frames of its empty stage, those of another
// size than width x height left out and counted in `skipped`; nullptr when no frame is left.
std::shared_ptr<const BackgroundModel> learnPlate(const std::vector<Image>& empty, int width,
                                                  int height, int* skipped = nullptr);

// Every rig camera's clean plate, nullptr for a camera without one (keyed on its green screen, or
// from masks).
using CameraPlates = std::vector<std::shared_ptr<const BackgroundModel>>;

// Every camera's clean plate from a session's plate/ frames (SessionReader::plateFrames). Throws
// Error naming the file for a plate frame that cannot be read.
CameraPlates sessionPlates(const SessionReader& session);
// `given` where there is one (learnt once for the evaluation's many parts), else sessionPlates.
CameraPlates platesOf(const SessionReader& session, const CameraPlates* given);

}  // namespace lumistage
