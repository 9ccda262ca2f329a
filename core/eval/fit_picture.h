#pragma once

#include <filesystem>
#include <vector>

#include "core/capture/image.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

// One picture of how the tracked body covers every camera's silhouette, at the silhouettes' cell
// resolution, the cameras side by side (up to four a row): each cell shows the camera's image at
// its centre, dimmed, tinted green where body and silhouette agree, blue where the silhouette has
// the actor and the body does not, red where the body lies outside the silhouette. `images` and
// the silhouettes are in the same camera order; `body` may be empty (nobody tracked: the
// silhouettes alone, in blue). Throws Error naming the file when it cannot be written.
void writeFitPicture(const std::filesystem::path& path, const std::vector<ImageView>& images,
                     const std::vector<const LowResSilhouette*>& silhouettes,
                     const std::vector<LowResSilhouette>& body);

}  // namespace lumistage
