#include "app/cli/rig_commands.h"

#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <string>

#include "app/cli/checks.h"
#include "core/base/output_path.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/ring_rig.h"
#include "core/geometry/stage_volume.h"

namespace lumistage {

namespace {

void printRig(const Rig& rig, const std::string& source) {
  fmt::print("{}: {} cameras on {} nodes\n", source, rig.cameraCount(), rig.nodeCount());
  fmt::print("stage: {}\n\n", chooseStage(rig).how);
  for (const RigNode& node : rig.nodes()) {
    std::string names;
    for (int c : node.cameras) names += (names.empty() ? "" : ", ") + rig.camera(c).name();
    fmt::print("node {:<10} host {:<16} cameras {}\n", node.name,
               node.host.empty() ? "(unassigned)" : node.host, names);
  }
  fmt::print("\n{:<10} {:<8} {:>10} {:>9} {:>9} {:>8} {:>8} {:>7} {:>7}   {:<26} {:<22}\n",
             "camera", "node", "size", "fx", "fy", "cx", "cy", "k1", "k2", "centre (m)",
             "looks along");
  // Rounded first so that -1e-17 prints as 0.000, not -0.000.
  auto round = [](const Eigen::Vector3d& v, double step) {
    return Eigen::Vector3d(((v / step).array().round() * step).matrix() + Eigen::Vector3d::Zero());
  };
  for (const Camera& c : rig.cameras()) {
    const Intrinsics& k = c.intrinsics();
    const Eigen::Vector3d centre = round(c.centre(), 1e-3), dir = round(c.viewingDirection(), 1e-2);
    fmt::print(
        "{:<10} {:<8} {:>10} {:>9.2f} {:>9.2f} {:>8.2f} {:>8.2f} {:>7.4f} {:>7.4f}   "
        "({:6.3f}, {:6.3f}, {:6.3f})   ({:5.2f}, {:5.2f}, {:5.2f})\n",
        c.name(), c.node(), fmt::format("{}x{}", c.width(), c.height()), k.fx, k.fy, k.cx, k.cy,
        c.distortion().k1, c.distortion().k2, centre.x(), centre.y(), centre.z(), dir.x(), dir.y(),
        dir.z());
  }
}

void writeResult(const RigImport& result, const std::string& out) {
  for (const std::string& note : result.notes) fmt::print(stderr, "note: {}\n", note);
  saveRig(result.rig, out);
  fmt::print("wrote {} ({} cameras on {} nodes)\n", out, result.rig.cameraCount(),
             result.rig.nodeCount());
}

}  // namespace

void addRigCommands(CLI::App& app) {
  CLI::App* rig = app.add_subcommand("rig", "Show, import and generate rig (calibration) files");
  rig->require_subcommand(1);

  auto show_file = std::make_shared<std::string>();
  CLI::App* show =
      rig->add_subcommand("show", "Print a rig file's cameras and nodes, or its error");
  show->add_option("file", *show_file, "rig file (YAML)")->required();
  show->callback([show_file] { printRig(loadRig(*show_file), *show_file); });

  struct ImportArgs {
    std::string svoboda, opencv, qualisys, toml, easymocap, out, image_size;
    int cameras_per_node = 3;
  };
  auto args = std::make_shared<ImportArgs>();
  CLI::App* import =
      rig->add_subcommand("import", "Convert another tool's calibration to a rig file");
  auto* svoboda = import->add_option("--svoboda", args->svoboda,
                                     "MultiCamSelfCal output folder (*.Pmat.cal, *.rad)");
  auto* opencv = import->add_option("--opencv", args->opencv, "OpenCV FileStorage file (YAML/XML)");
  auto* qualisys = import->add_option("--qualisys", args->qualisys,
                                      "Qualisys Track Manager calibration (.qca.txt)");
  auto* toml =
      import->add_option("--toml", args->toml, "Pose2Sim or anipose calibration (Calib*.toml)");
  auto* easymocap = import->add_option("--easymocap", args->easymocap,
                                       "EasyMocap calibration folder (intri.yml, extri.yml)");
  svoboda->excludes(opencv);
  qualisys->excludes(svoboda)->excludes(opencv);
  toml->excludes(svoboda)->excludes(opencv)->excludes(qualisys);
  easymocap->excludes(svoboda)->excludes(opencv)->excludes(qualisys)->excludes(toml);
  import->add_option("--image-size", args->image_size,
                     "WIDTHxHEIGHT (needed with --svoboda, and --easymocap without W_ and H_)");
  import
      ->add_option("--cameras-per-node", args->cameras_per_node,
                   "cameras per node PC; cameras are dealt to nodes in turn")
      ->capture_default_str();
  import->add_option("-o,--out", args->out, "rig file to write")->required();
  import->callback([args, import] {
    refuseOutputOverInputs("--out", args->out,
                           {{"--svoboda", args->svoboda},
                            {"--opencv", args->opencv},
                            {"--qualisys", args->qualisys},
                            {"--toml", args->toml},
                            {"--easymocap", args->easymocap}});
  RigImportOptions options;
  options.cameras_per_node = args->cameras_per_node;
  if (!args->image_size.empty()) {
    char x = 0;
    if (std::sscanf(args->image_size.c_str(), "%d%c%d", &options.width, &x, &options.height) != 3 ||
        x != 'x' || options.width <= 0 || options.height <= 0) {
      throw CLI::ValidationError(
          "--image-size", "expected WIDTHxHEIGHT, e.g. 1024x768, got '" + args->image_size + "'");
    }
  }
  if (!args->svoboda.empty()) {
    writeResult(importSvobodaRig(args->svoboda, options), args->out);
  } else if (!args->opencv.empty()) {
    writeResult(importOpenCvRig(args->opencv, options), args->out);
  } else if (!args->qualisys.empty()) {
    writeResult(importQualisysRig(args->qualisys, options), args->out);
  } else if (!args->toml.empty()) {
    writeResult(importTomlRig(args->toml, options), args->out);
  } else if (!args->easymocap.empty()) {
    writeResult(importEasyMocapRig(args->easymocap, options), args->out);
  } else {
    throw CLI::RequiredError("--svoboda, --opencv, --qualisys, --toml or --easymocap");
  }
});

auto spec = std::make_shared<RingRigSpec>();
auto ring_out = std::make_shared<std::string>();
CLI::App* ring = rig->add_subcommand(
    "ring", "Write a ring of cameras around the stage (defaults: the reference rig)");
ring->add_option("--cameras", spec->cameras, "number of cameras")
    ->check(within(1, 256))
    ->capture_default_str();
ring->add_option("--cameras-per-node", spec->cameras_per_node)
    ->check(within(1, 64))
    ->capture_default_str();
ring->add_option("--width", spec->width)->check(within(16, 16384))->capture_default_str();
ring->add_option("--height", spec->height)->check(within(16, 16384))->capture_default_str();
ring->add_option("--radius", spec->radius_m, "distance from the stage centre (m)")
    ->check(within(0.5, 100))
    ->capture_default_str();
ring->add_option("--vertical-fov", spec->vertical_fov_deg, "degrees")
    ->check(within(1, 179))
    ->capture_default_str();
ring->add_option("-o,--out", *ring_out, "rig file to write")->required();
ring->callback([spec, ring_out] {
  const Rig rig = makeRingRig(*spec);
  saveRig(rig, *ring_out);
  fmt::print("wrote {} ({} cameras on {} nodes)\n", *ring_out, rig.cameraCount(), rig.nodeCount());
});
}  // namespace lumistage

}  // namespace lumistage
