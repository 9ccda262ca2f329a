#pragma once

#include <memory>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/capture/image.h"
#include "core/capture/session_reader.h"
#include "core/imaging/keyer.h"

namespace lumistage {

// A camera's clean plate (BackgroundModel) learnt from frames of its empty stage, those of another
// size than width x height left out and counted in `skipped`; nullptr when no frame is left.
std::shared_ptr<const BackgroundModel> learnPlate(const std::vector<Image>& empty, int width,
                                                  int height, int* skipped = nullptr);
// Rig camera `camera`'s clean plate from the frames of the empty stage its source filmed
// (FrameSource::plateImages), as learnPlate; nullptr when it filmed none.
std::shared_ptr<const BackgroundModel> sourcePlate(FrameSource& source, int camera,
                                                   int* skipped = nullptr);

// Every camera's clean plate from a session's plate/ frames (SessionReader::plateFrames). Throws
// Error naming the file for a plate frame that cannot be read.
CameraPlates sessionPlates(const SessionReader& session);
// `given` where there is one (learnt once for the evaluation's many parts), else sessionPlates.
CameraPlates platesOf(const SessionReader& session, const CameraPlates* given);

}  // namespace lumistage
