#pragma once

// The reference virtual studio (resources/studio/reference.yaml) as the tests film it: its actor,
// clothes, screen and light, with a lighter actor mesh or a smaller rig.
#include <string>

#include "core/geometry/ring_rig.h"
#include "core/sim/studio_config.h"

namespace lumistage::testing {

// The reference studio, its actor meshed with about `actor_vertices` vertices.
inline StudioConfig referenceStudio(int actor_vertices) {
  StudioConfig config =
      loadStudioConfig(std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/studio/reference.yaml");
  config.actor.target_vertices = actor_vertices;
  return config;
}

// The same, filmed by a ring of `cameras` cameras of width x height instead of the reference rig.
inline StudioConfig referenceStudioOnRing(int actor_vertices, int cameras, int width, int height) {
  StudioConfig config = referenceStudio(actor_vertices);
  RingRigSpec spec;
  spec.cameras = cameras;
  spec.width = width;
  spec.height = height;
  config.rig = makeRingRig(spec);
  return config;
}

}  // namespace lumistage::testing
