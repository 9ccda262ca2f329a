#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "core/body/human_model.h"
#include "core/capture/session_writer.h"
#include "core/geometry/rig.h"
#include "core/refine/refine_config.h"
#include "core/sim/motion_placement.h"
#include "core/sim/studio_renderer.h"

namespace lumistage {

// A virtual studio: the rig that films it, the actor, the motion, the look. Read from a studio
// config file (YAML, documented in docs/virtual-studio.md; resources/studio/reference.yaml is the
// reference stage).
struct StudioConfig {
  std::filesystem::path rig_file;  // as resolved (relative paths are relative to the config)
  Rig rig;
  HumanModelSpec actor;
  std::string clip = "walk";       // a built-in clip name
  std::filesystem::path bvh_file;  // or a BVH motion (takes precedence when set)
  double fps = 30.0;
  MotionPlacement placement;
  StudioLook look;
  PixelFormat pixel_format = PixelFormat::kRgb8;
  uint32_t seed = 1;
  RefineConfig refine;  // the `refine:` section: the mesh refinement's parameters
};

// Throws Error with file:line: key for anything malformed (see YamlReader).
StudioConfig loadStudioConfig(const std::filesystem::path& path);

// The config as a studio config file that loadStudioConfig reads back to the same stage, its rig
// given as `rig_file` (written as it is; relative paths are relative to the config) and a BVH
// motion by its absolute path. The `refine:` section is left out (the defaults).
std::string formatStudioConfig(const StudioConfig& config, const std::string& rig_file);

}  // namespace lumistage
