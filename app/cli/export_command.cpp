#include "app/cli/export_command.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>

#include "app/cli/checks.h"
#include "app/cli/progress.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/body/bvh.h"
#include "core/body/fbx_export.h"
#include "core/body/human_model.h"
#include "core/body/mesh_sequence_io.h"
#include "core/capture/session_reader.h"
#include "core/eval/eval_report.h"
#include "core/eval/mocap_eval.h"
#include "core/imaging/clean_plate.h"
#include "core/net/posed_body.h"
#include "core/refine/frame_refiner.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

}  // namespace

void addExportCommand(CLI::App& app) {
  struct Args {
    std::string session, out;
    int frames = 0;
    bool bvh = false, fbx = false, glb = false, ply = false, obj = false, unrefined = false;
    BodyChoice body;
  };
  auto args = std::make_shared<Args>();
  CLI::App* exp = app.add_subcommand(
      "export",
      "Capture a session for other tools: the tracked skeleton as BVH or FBX (with the skinned "
      "body), the captured surface as an animated glTF and per-frame PLY/OBJ (default: --bvh "
      "--glb)");
  exp->add_option("--session", args->session, "the recorded session")->required();
  exp->add_option("-o,--out", args->out, "folder to write into (created)")->required();
  exp->add_option("--frames", args->frames, "only the first N frames (default: all)")
      ->check(within(1, 1e9));
  exp->add_flag("--bvh", args->bvh, "skeleton.bvh: the tracked motion, the actor's bone lengths");
  exp->add_flag("--fbx", args->fbx,
                "actor.fbx: the tracked motion on the body's skeleton (the generic human's, or "
                "--body FILE's), with the skinned body (binary FBX, for Blender, Maya, Unity, "
                "Unreal)");
  exp->add_flag("--glb", args->glb, "surface.glb: the surface of every frame, animated");
  exp->add_flag("--ply", args->ply, "meshes/NNNNNN.ply: the surface of each frame");
  exp->add_flag("--obj", args->obj, "meshes/NNNNNN.obj: the same as OBJ, with normals");
  exp->add_flag("--unrefined", args->unrefined,
                "the posed generic mesh as it is, without the refinement from the images");
  addBodyOption(*exp, args->body);
  exp->callback([args] {
    if (!args->bvh && !args->fbx && !args->glb && !args->ply && !args->obj)
      args->bvh = args->glb = true;
    refuseOutputOverInputs("--out", args->out, {{"--session", args->session}});
    const SessionReader session(args->session);
    const fs::path out(args->out);
    std::error_code ec;
    fs::create_directories(args->ply || args->obj ? out / "meshes" : out, ec);
    if (ec) throw Error(out.string() + ": cannot create: " + ec.message());

    // The studio's motion capture, offline: every camera keyed at low resolution, tracked.
    const SkinnedMesh generic = loadBody(args->body);
    MocapEvalOptions options;
    options.max_frames = args->frames;
    EvalReport report;
    fmt::print("tracking {} ...\n", args->session);
    const MocapEvalResult mocap = evaluateMocap(session, generic, options, report);
    size_t first = 0;
    while (first < mocap.valid.size() && !mocap.valid[first]) ++first;
    if (first == mocap.valid.size())
      throw Error(args->session + ": the actor was never tracked (no T- or A-pose to start from?)");

    // Frames before the first tracked one are left out; a frame where the actor was lost keeps
    // the last tracked pose (counted below).
    MotionClip clip;
    clip.name = fs::path(args->session).filename().string();
    clip.fps = session.fps();
    std::vector<std::vector<Eigen::Vector3d>> joints;  // the tracked joints of clip.frames
    int held = 0;
    for (size_t f = first; f < mocap.poses.size(); ++f) {
      const bool tracked = mocap.valid[f];
      held += !tracked;
      clip.frames.push_back(tracked ? mocap.poses[f] : clip.frames.back());
      joints.push_back(tracked ? mocap.joints[f] : joints.back());
    }
    if (args->bvh) {
      saveBvh(clip, mocap.skeleton, out / "skeleton.bvh");
      fmt::print("wrote {}\n", (out / "skeleton.bvh").string());
    }
    if (args->fbx) {
      // The body as the studio poses it (posed_body.h): its own skeleton's angles fitted to the
      // tracked joints, scaled to the actor.
      MotionClip body_clip;
      body_clip.name = clip.name;
      body_clip.fps = clip.fps;
      double scale = 1;
      for (size_t i = 0; i < clip.frames.size(); ++i) {
        const PoseData data =
            poseMessageFor(generic.skeleton, mocap.skeleton, clip.frames[i], joints[i]);
        body_clip.frames.push_back(poseFromMessage(data, generic.skeleton.jointCount()));
        if (i == 0) scale = data.scale;  // one for the actor: from the rest skeletons
      }
      saveAnimatedBodyFbx(generic, body_clip, out / "actor.fbx", scale);
      fmt::print("wrote {}\n", (out / "actor.fbx").string());
    }

    // The surface: the generic human where the tracker sees the actor, refined from the images.
    std::vector<TriangleMesh> meshes;
    FrameRefiner refiner(session.rig(), RefineConfig{}, generic.rest.vertexCount(),
                         generic.rest.triangles);
    refiner.setPlates(sessionPlates(session));
    std::vector<CameraFrame> images;
    Pose pose;
    std::vector<Eigen::Affine3f> transforms;
    Eigen::Matrix3Xf positions, normals;
    const bool surfaces = args->glb || args->ply || args->obj;
    for (size_t i = 0; surfaces && i < clip.frames.size(); ++i) {
      TriangleMesh mesh;
      mesh.triangles = generic.rest.triangles;
      posedBodyMesh(generic,
                    poseMessageFor(generic.skeleton, mocap.skeleton, clip.frames[i], joints[i]),
                    pose, transforms, positions, normals);
      if (args->unrefined) {
        mesh.positions = positions;
        mesh.normals = normals;
      } else {
        session.readFrame(int(first + i), images);
        refiner.refine(images, positions, normals, mesh.positions);
        mesh.computeNormals();
      }
      const int64_t frame = session.frameId(int(first + i));
      if (args->ply) saveMeshPly(out / "meshes" / fmt::format("{:06}.ply", frame), mesh);
      if (args->obj) saveMeshObj(out / "meshes" / fmt::format("{:06}.obj", frame), mesh);
      if (args->glb) meshes.push_back(std::move(mesh));
      printProgress("surfaces", int(i + 1), int(clip.frames.size()));
    }
    if (args->glb) {
      saveMeshSequenceGlb(out / "surface.glb", meshes, session.fps());
      fmt::print("wrote {}\n", (out / "surface.glb").string());
    }
    fmt::print("{} frames exported from frame {}; {} held the last tracked pose\n",
               clip.frames.size(), session.frameId(int(first)), held);
  });
}

}  // namespace lumistage
