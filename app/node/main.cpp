// lumistage-node: the headless worker on each camera PC. In this build it loads the rig and checks
// that this node is in it, listing the cameras it owns; capture and the link to the studio come
// with the capture and pipeline work (see README, "Status").
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <exception>

#include "core/geometry/rig_file.h"

int main(int argc, char** argv) {
  CLI::App app{"Lumistage camera node: owns the cameras of one PC"};
  std::string rig_path, node_name;
  app.add_option("--rig", rig_path, "rig file (YAML)")->required();
  app.add_option("--node", node_name, "this node's name in the rig")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const lumistage::Rig rig = lumistage::loadRig(rig_path);
    const std::optional<int> index = rig.findNode(node_name);
    if (!index) {
      std::string names;
      for (const auto& n : rig.nodes()) names += (names.empty() ? "" : ", ") + n.name;
      fmt::print(stderr, "lumistage-node: error: {}: no node '{}'; the rig's nodes are: {}\n",
                 rig_path, node_name, names);
      return 1;
    }
    const lumistage::RigNode& node = rig.nodes()[*index];
    fmt::print("node {} ({}): {} cameras\n", node.name,
               node.host.empty() ? "no host assigned" : node.host, node.cameras.size());
    for (int c : node.cameras) {
      const lumistage::Camera& camera = rig.camera(c);
      fmt::print("  {} {}x{}\n", camera.name(), camera.width(), camera.height());
    }
    fmt::print(stderr,
               "lumistage-node: configuration is valid; this build does not capture or serve "
               "frames yet (see README, \"Status\")\n");
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lumistage-node: error: {}\n", e.what());
    return 1;
  }
}
