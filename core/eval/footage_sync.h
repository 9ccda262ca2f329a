#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/geometry/rig.h"

namespace lumistage {

// How many frames each camera's footage runs behind the others, found from the footage's masks of
// the actor (another tool's: MASKS/CAMERA/FFFFFF.png by the footage's frame numbers, as
// `lumistage session import --masks` takes them). Cameras without a shared trigger start a few
// frames apart; a camera out of step sees the limbs that moved where the others do not, so the
// visual hull carved from all the masks explains less of each. The search keeps the offsets under
// which the hull explains the most of every mask (docs/session-format.md).
struct FootageSyncOptions {
  int range = 10;                    // frames searched each way
  std::map<std::string, int> fixed;  // cameras whose offset is known (as --offset gives them)
  double voxel_m = 0.03;             // the hull's voxels
};

struct FootageSyncCamera {
  std::string camera;
  int offset = 0;  // its frame k + offset is taken with the others' frame k
  bool fixed = false;
  // The share of its masks' area the hull explains at the offsets found, and with none.
  double agreement = 0, unshifted = 0;
  // The mean agreement over every camera with this one at its offset and at its best other
  // offset (the others as found, on the frames both share): how clearly the offset stands out.
  double best_agreement = 0;
  int runner_up = 0;
  double runner_up_agreement = 0;
};

struct FootageSync {
  std::vector<FootageSyncCamera> cameras;  // the rig's order
  double agreement = 0, unshifted = 0;     // over every camera and frame compared
  int frames = 0;                          // frames every camera has a mask of, as found
  int spacing = 1;  // the masks' frame spacing: offsets are found in multiples of it
  std::vector<std::string> notes;
};

// Throws Error naming the folder or file: a camera without masks, a mask of another size than its
// camera (up to 16 pixels smaller is a crop, as footage import takes it), a mask that does not
// read, or fewer than 3 frames every camera has a mask of. `progress(done, total)` as the masks
// load and the offsets are tried.
FootageSync estimateFootageSync(const Rig& rig, const std::filesystem::path& masks,
                                const FootageSyncOptions& options = {},
                                const std::function<void(int, int)>& progress = {});

// The estimate as a table a person reads (camera, offset, agreement, runner-up).
std::string describeFootageSync(const FootageSync& sync);

}  // namespace lumistage
