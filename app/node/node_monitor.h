#pragma once

#include <atomic>
#include <string>

#include "core/pipeline/camera_node.h"

namespace lumistage {

// `lumistage-node --monitor`: a small window on the node's own PC (GLFW + Dear ImGui) with its
// cameras' live images, their silhouettes and counters, refreshed a few times a second while the
// node works. Returns when the window is closed or `stop` is set; throws Error in words when no
// window can be opened (no display).
// With `screenshot_png`, saves the window there once every camera has shown a picture for a
// couple of seconds, then returns.
void runNodeMonitor(CameraNode& node, const Rig& rig, const std::string& node_name,
                    const std::atomic<bool>& stop, const std::string& screenshot_png = {});

}  // namespace lumistage
