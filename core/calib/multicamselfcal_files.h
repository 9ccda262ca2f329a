#pragma once

#include <filesystem>

#include "core/calib/wand_session.h"
#include "core/geometry/rig.h"

namespace lumistage {

// Interchange with Svoboda's MultiCamSelfCal (Matlab), so that a studio can check our solve
// against the toolbox it knows, or use the toolbox's result (imported by importSvobodaRig).

// The toolbox's input, in `folder`: points.dat (3·cameras rows by samples columns: x, y, 1 of
// each camera, NaN where missing), IdMat.dat (cameras by samples, 1 where seen) and Res.dat
// (cameras rows: width height). Pixels are written as they are (0-based, OpenCV's convention);
// the toolbox's projection matrices then map to the same convention, which importSvobodaRig reads.
void writeMultiCamSelfCalInput(const WandSession& session, const std::filesystem::path& folder);

// A rig as the toolbox writes its result: NAME.Pmat.cal (P = K[R|t], 3 rows) and NAME.rad (K and
// kc1..kc4 = k1 k2 p1 p2) per camera.
void writeMultiCamSelfCalOutput(const Rig& rig, const std::filesystem::path& folder);

}  // namespace lumistage
