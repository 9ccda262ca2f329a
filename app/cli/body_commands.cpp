#include "app/cli/body_commands.h"

#include <fmt/format.h>

#include <memory>

#include "app/cli/checks.h"
#include "core/body/human_model.h"
#include "core/body/mesh_io.h"

namespace lumistage {

void addBodyCommands(CLI::App& app) {
  CLI::App* body = app.add_subcommand("body", "The generic human and other rigged meshes");
  body->require_subcommand(1);

  auto out = std::make_shared<std::string>();
  auto vertices = std::make_shared<int>(2000);
  CLI::App* generate = body->add_subcommand(
      "generate", "Write the generic human (closed, manifold, skinned, T-pose) as glTF 2.0");
  generate->add_option("-o,--out", *out, "file to write (.glb or .gltf)")->required();
  generate->add_option("--vertices", *vertices, "about this many vertices")
      ->check(within(200, 200000))
      ->capture_default_str();
  generate->callback([out, vertices] {
    HumanModelSpec spec;
    spec.target_vertices = *vertices;
    const SkinnedMesh human = makeHumanModel(spec);
    saveSkinnedMeshGltf(human, *out);
    fmt::print("wrote {}: {} vertices, {} triangles, {} joints\n", *out, human.rest.vertexCount(),
               human.rest.triangles.size(), human.skeleton.jointCount());
  });

  auto file = std::make_shared<std::string>();
  CLI::App* show =
      body->add_subcommand("show", "Print a rigged mesh's skeleton and surface, or its error");
  show->add_option("file", *file, "glTF/GLB, FBX, COLLADA...")->required();
  show->callback([file] {
    const SkinnedMesh mesh = loadSkinnedMesh(*file);
    const std::string manifold = checkClosedManifold(mesh.rest);
    const Eigen::Vector3f lo = mesh.rest.positions.rowwise().minCoeff();
    const Eigen::Vector3f hi = mesh.rest.positions.rowwise().maxCoeff();
    fmt::print("{}: {} vertices, {} triangles, {}\n", *file, mesh.rest.vertexCount(),
               mesh.rest.triangles.size(),
               manifold.empty() ? "closed and manifold" : "NOT closed and manifold: " + manifold);
    fmt::print("extent: x {:.3f}..{:.3f}, y {:.3f}..{:.3f}, z {:.3f}..{:.3f} m\n", lo.x(), hi.x(),
               lo.y(), hi.y(), lo.z(), hi.z());
    fmt::print("{} joints:\n", mesh.skeleton.jointCount());
    for (int j = 0; j < mesh.skeleton.jointCount(); ++j) {
      const Joint& joint = mesh.skeleton.joint(j);
      const Eigen::Vector3d p = mesh.skeleton.restPositions()[j];
      fmt::print("  {:<16} parent {:<16} at ({:6.3f}, {:6.3f}, {:6.3f})\n", joint.name,
                 joint.parent < 0 ? "-" : mesh.skeleton.joint(joint.parent).name, p.x(), p.y(),
                 p.z());
    }
  });
}

}  // namespace lumistage
