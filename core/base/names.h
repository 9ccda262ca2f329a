#pragma once

#include <string_view>

namespace lumistage {

// Whether a name may be used for a camera, a node or a take: 1-64 characters of [A-Za-z0-9_.-],
// not starting with '.' or '-'. Names become file and folder names in recordings. Depends on
// nothing, so that the message decoder (and its fuzz target) can check names with it.
bool isValidName(std::string_view name);

// Names with their runs of digits compared as numbers: "cam2" before "cam10", "cam_9" before
// "cam_10"; otherwise character by character.
bool naturalLess(std::string_view a, std::string_view b);

}  // namespace lumistage
