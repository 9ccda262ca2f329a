// The actor's body on the command line, run as a user runs it: body show, a body from a file
// through eval and run, and export of the capture.
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/base/atomic_file.h"
#include "core/body/bvh.h"
#include "core/body/human_model.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::kCli;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

// Assimp's COLLADA parser recurses per nested node: 100,000 of them ended `body show` with
// SIGSEGV. The import runs in a child process: a crash inside it is an error naming the file,
// a refused file keeps its message, and a good file prints as before.
TEST(Cli, BodyShowSaysSoWhenTheImportCrashesOrIsRefused) {
  const fs::path deep = tempPath("deep.dae");
  {
    std::ofstream out(deep);
    out << "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/"
           "COLLADASchema\" version=\"1.4.1\">\n<library_visual_scenes><visual_scene id=\"s\">";
    for (int i = 0; i < 100000; ++i) out << "<node id=\"n\">";
    for (int i = 0; i < 100000; ++i) out << "</node>";
    out << "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/>"
           "</scene></COLLADA>\n";
  }
  Result r = run(kCli + " body show " + deep.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lumistage: error: " + deep.string() +
                          ": the import crashed inside the mesh library"),
            std::string::npos)
      << r.output;
  const fs::path bad = tempPath("bad.fbx");
  std::ofstream(bad) << "garbage\n";
  r = run(kCli + " body show " + bad.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lumistage: error: " + bad.string() + ": cannot read it as a mesh"),
            std::string::npos)
      << r.output;
  const fs::path good = tempPath("good.glb");
  ASSERT_EQ(run(kCli + " body generate --vertices 500 --out " + good.string()).exit_code, 0);
  r = run(kCli + " body show " + good.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("closed and manifold"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("24 joints:"), std::string::npos) << r.output;
  for (const fs::path& f : {deep, bad, good}) fs::remove(f);
}

// --body FILE (Khronos' CesiumMan from ../shared/realdata, where present): body show prints how
// its joints map onto ours; eval tracks with it; run starts nodes that pose the same file (a node
// posing another body would say its offsets are "not used").
TEST(Cli, TheActorsOwnBodyFromAFileIsShownEvaluatedAndRun) {
  const fs::path cesium = testing::realData() / "bodies" / "CesiumMan.glb";
  if (!fs::exists(cesium)) GTEST_SKIP() << "no " << cesium.string();
  const Result shown = run(kCli + " body show " + cesium.string());
  ASSERT_EQ(shown.exit_code, 0) << shown.output;
  EXPECT_NE(shown.output.find("left_elbow      <- Skeleton_arm_joint_L__3_"), std::string::npos)
      << shown.output;
  const fs::path folder = tempPath("body_file");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6"));
  const Result eval = run(kCli + " eval --session " + (folder / "session").string() +
                          " --mocap-only --body " + cesium.string());
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("frames_tracked                        6"), std::string::npos)
      << eval.output;
  const Result r = run(kCli + " run --session " + (folder / "session").string() +
                       " --frames 12 --seconds 60 --body " + cesium.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 frames in all"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("not used"), std::string::npos) << r.output;
  // Exported as FBX: that body, skinned, on our skeleton (its vertices, not the generic human's).
  const Result exported =
      run(kCli + " export --session " + (folder / "session").string() + " --out " +
          (folder / "export").string() + " --fbx --unrefined --body " + cesium.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const std::string fbx = readFile(folder / "export" / "actor.fbx");
  EXPECT_NE(fbx.find(std::string("left_elbow\0\x01Model", 17)), std::string::npos);
  // The mesh's Vertices node: its array property ('d', then its length: three a vertex).
  const size_t at = fbx.find("Vertices");
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(fbx[at + 8], 'd');
  uint32_t values = 0;
  std::memcpy(&values, fbx.data() + at + 9, 4);
  EXPECT_EQ(int(values), 3 * loadBody(parseBodyChoice(cesium.string())).rest.vertexCount());
  EXPECT_NE(int(values), 3 * loadGenericHuman().rest.vertexCount());
  fs::remove_all(folder);
}

TEST(Cli, ExportWritesTheCaptureAsBvhGltfAndPlyThatReadBack) {
  const fs::path folder = tempPath("export");
  const fs::path session = folder / "session", out = folder / "export";
  ASSERT_TRUE(synthRingSession(folder, "--cameras 8 --width 640 --height 480",
                               "actor:\n  vertices: 2000\n", "--frames 5"));
  Result r = run(kCli + " export --session " + session.string() + " --out " + out.string() +
                 " --bvh --fbx --glb --ply");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("5 frames exported"), std::string::npos) << r.output;

  // The BVH reads back onto the generic skeleton, a frame per session frame.
  const SkinnedMesh generic = loadGenericHuman();
  const MotionClip clip = loadBvh(out / "skeleton.bvh", generic.skeleton);
  EXPECT_EQ(clip.frames.size(), 5u);
  // The FBX (binary, for Blender: core/body/fbx_export_test reads such files back): every joint
  // of the generic skeleton as a skeleton node, the skinned body, one take.
  const std::string fbx = readFile(out / "actor.fbx");
  EXPECT_EQ(fbx.substr(0, 20), "Kaydara FBX Binary  ");
  for (const Joint& joint : generic.skeleton.joints())
    EXPECT_NE(fbx.find(joint.name + std::string("\0\x01Model", 7)), std::string::npos)
        << joint.name;
  EXPECT_NE(fbx.find(std::string("body\0\x01Model", 11)), std::string::npos);
  EXPECT_NE(fbx.find("AnimStack"), std::string::npos);
  // The animated glTF: a mesh of the generic human's size per frame, a node animation.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile((out / "surface.glb").string(), 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 5u);
  EXPECT_EQ(int(scene->mMeshes[4]->mNumVertices), generic.rest.vertexCount());
  EXPECT_EQ(scene->mNumAnimations, 1u);
  // The refined surface stands where the actor does: on the floor, about the actor's height (this
  // actor is the generic human, 1.74 m; glTF is Y up). The tracker needs the cameras' low-res
  // silhouettes to resolve the limbs: 640x480 here, not less.
  float low = 1e9f, high = -1e9f;
  for (unsigned v = 0; v < scene->mMeshes[4]->mNumVertices; ++v) {
    low = std::min(low, scene->mMeshes[4]->mVertices[v].y);
    high = std::max(high, scene->mMeshes[4]->mVertices[v].y);
  }
  EXPECT_NEAR(low, 0.0f, 0.08f);
  EXPECT_NEAR(high - low, 1.74f, 0.1f);
  EXPECT_TRUE(fs::exists(out / "meshes" / "000004.ply"));

  // The last frame's image of a camera cut short (the disk filled): the session ends before it,
  // and the command says so, naming the file, instead of exporting one frame less in silence.
  const fs::path cut = session / "cam03" / "000004.png";
  fs::resize_file(cut, fs::file_size(cut) / 2);
  r = run(kCli + " export --session " + session.string() + " --out " +
          (folder / "export_cut").string() + " --bvh");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 frames exported"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cam03/000004.png"), std::string::npos) << r.output;

  // A session nobody can be tracked in: a clear error, nothing half-written claimed.
  r = run(kCli + " export --session " + (folder / "nothing").string() + " --out " +
          (folder / "export2").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nothing"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
