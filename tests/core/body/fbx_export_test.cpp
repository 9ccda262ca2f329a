// FBX out through Assimp's exporter. The ASCII file reads back through Assimp's importer with the
// same bones, frames and joint positions; the binary one (what Blender reads; Assimp 5.2's reader
// refuses its own binary writer's files) is walked node by node here and holds the same scene.
#include "core/body/fbx_export.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "tests/core/body/body_test_meshes.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

using testing::errorOf;
using testing::testFolder;

constexpr int kFrames = 12;
constexpr double kFps = 30;

// A walk, an arm raised and the head turned: every joint's angles change over the clip.
MotionClip testClip(const Skeleton& skeleton) {
  MotionClip clip;
  clip.name = "walk";
  clip.fps = kFps;
  for (int f = 0; f < kFrames; ++f) {
    Pose pose = Pose::rest(skeleton.jointCount());
    pose.root_translation_m = Eigen::Vector3d(0.02 * f, 0.05 * f, 0.01 * std::sin(f));
    pose.angles_rad[0] = Eigen::Vector3d(0.02 * f, -0.01 * f, 0.05 * f);
    for (int j = 1; j < skeleton.jointCount(); ++j)
      pose.angles_rad[j] = Eigen::Vector3d(0.3 * std::sin(0.4 * f + j), 0.2 * std::cos(0.3 * f),
                                           0.25 * std::sin(0.2 * f - j));
    skeleton.clampToLimits(pose);
    clip.frames.push_back(pose);
  }
  return clip;
}

// Our world (z up, metres) to the file's (Y up, centimetres), scaled by `scale`.
aiVector3D inFile(const Eigen::Vector3d& p, double scale) {
  const Eigen::Vector3d y = 100 * scale * (yUpToOurs() * p);
  return {float(y.x()), float(y.y()), float(y.z())};
}

const aiNodeAnim* channelOf(const aiAnimation& animation, const std::string& node) {
  for (unsigned c = 0; c < animation.mNumChannels; ++c)
    if (node == animation.mChannels[c]->mNodeName.C_Str()) return animation.mChannels[c];
  return nullptr;
}

// A node's world transform at key k of the animation (its own transform where it has no channel).
aiMatrix4x4 worldAt(const aiNode* node, const aiAnimation& animation, unsigned k) {
  aiMatrix4x4 world;
  for (; node; node = node->mParent) {
    aiMatrix4x4 local = node->mTransformation;
    if (const aiNodeAnim* channel = channelOf(animation, node->mName.C_Str())) {
      const aiVector3D& t = channel->mPositionKeys[k].mValue;
      local = aiMatrix4x4(aiVector3D(1, 1, 1), channel->mRotationKeys[k].mValue, t);
    }
    world = local * world;
  }
  return world;
}

TEST(FbxExport, AsciiReadsBackThroughAssimpWithTheBonesFramesAndPoses) {
  const SkinnedMesh body = testing::makeHumanMesh();
  const MotionClip clip = testClip(body.skeleton);
  const std::filesystem::path file = testFolder("fbx_export") / "actor.fbx";
  constexpr double kScale = 1.05;
  saveAnimatedBodyFbx(body, clip, file, kScale, FbxEncoding::kAscii);

  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_JoinIdenticalVertices);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  // The skinned body: every vertex, a bone per joint by the joint's name, the weights kept.
  ASSERT_EQ(scene->mNumMeshes, 1u);
  const aiMesh& mesh = *scene->mMeshes[0];
  EXPECT_EQ(int(mesh.mNumVertices), body.rest.vertexCount());
  EXPECT_EQ(int(mesh.mNumFaces), int(body.rest.triangles.size()));
  std::set<std::string> bones, joints;
  double weight_sum = 0;
  for (unsigned b = 0; b < mesh.mNumBones; ++b) {
    bones.insert(mesh.mBones[b]->mName.C_Str());
    for (unsigned w = 0; w < mesh.mBones[b]->mNumWeights; ++w)
      weight_sum += mesh.mBones[b]->mWeights[w].mWeight;
  }
  for (const Joint& joint : body.skeleton.joints()) joints.insert(joint.name);
  EXPECT_EQ(bones, joints);
  EXPECT_NEAR(weight_sum, body.rest.vertexCount(), 1e-3);
  // The rest mesh stands where ours does, in the file's axes and centimetres.
  float low = 1e9f, high = -1e9f;
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    low = std::min(low, mesh.mVertices[v].y);
    high = std::max(high, mesh.mVertices[v].y);
  }
  EXPECT_NEAR(high - low,
              100 * kScale * body.rest.positions.row(2).maxCoeff() -
                  100 * kScale * body.rest.positions.row(2).minCoeff(),
              0.01);

  // One take of the clip's name, a key per frame on every joint at the clip's times.
  ASSERT_EQ(scene->mNumAnimations, 1u);
  const aiAnimation& animation = *scene->mAnimations[0];
  EXPECT_EQ(std::string(animation.mName.C_Str()), "walk");
  EXPECT_DOUBLE_EQ(animation.mTicksPerSecond, kFps);  // the file's rate is the clip's
  EXPECT_NEAR(animation.mDuration, kFrames - 1, 1e-3);
  EXPECT_EQ(int(animation.mNumChannels), body.skeleton.jointCount());
  for (const Joint& joint : body.skeleton.joints()) {
    const aiNodeAnim* channel = channelOf(animation, joint.name);
    ASSERT_NE(channel, nullptr) << joint.name;
    ASSERT_EQ(int(channel->mNumPositionKeys), kFrames) << joint.name;
    ASSERT_EQ(int(channel->mNumRotationKeys), kFrames) << joint.name;
    for (int f = 0; f < kFrames; ++f)
      EXPECT_NEAR(channel->mRotationKeys[f].mTime / animation.mTicksPerSecond, f / kFps, 1e-4);
  }
  // Every joint of every frame where our forward kinematics puts it (within 0.1 mm).
  std::vector<Eigen::Vector3d> expected;
  for (int f = 0; f < kFrames; ++f) {
    body.skeleton.jointPositions(clip.frames[f], expected);
    for (int j = 0; j < body.skeleton.jointCount(); ++j) {
      const aiNode* node = scene->mRootNode->FindNode(body.skeleton.joint(j).name.c_str());
      ASSERT_NE(node, nullptr);
      const aiMatrix4x4 world = worldAt(node, animation, unsigned(f));
      const aiVector3D want = inFile(expected[j], kScale);
      EXPECT_NEAR(world.a4, want.x, 0.01) << body.skeleton.joint(j).name << " frame " << f;
      EXPECT_NEAR(world.b4, want.y, 0.01) << body.skeleton.joint(j).name << " frame " << f;
      EXPECT_NEAR(world.c4, want.z, 0.01) << body.skeleton.joint(j).name << " frame " << f;
    }
  }
}

// A node of a binary FBX file: its name, its properties that are strings, its arrays of 64-bit
// integers (KeyTime) and floats (KeyValueFloat), its children.
struct FbxNode {
  std::string name;
  std::vector<std::string> strings;
  std::vector<double> numbers;  // its properties that are numbers, in order
  std::vector<int64_t> longs;
  std::vector<float> floats;
  std::vector<FbxNode> children;

  void collect(const std::string& wanted, std::vector<const FbxNode*>& found) const {
    if (name == wanted) found.push_back(this);
    for (const FbxNode& child : children) child.collect(wanted, found);
  }
};

template <typename T>
T take(const std::string& d, size_t& at) {
  T v{};
  if (at + sizeof(T) > d.size()) throw std::runtime_error("past the end");
  std::memcpy(&v, d.data() + at, sizeof(T));
  at += sizeof(T);
  return v;
}

// FBX 7.5's binary node records (64-bit offsets), arrays stored uncompressed (as Assimp writes).
bool readNode(const std::string& d, size_t& at, FbxNode& node) {
  const uint64_t end = take<uint64_t>(d, at), properties = take<uint64_t>(d, at);
  take<uint64_t>(d, at);  // the properties' length
  const uint8_t name_length = take<uint8_t>(d, at);
  if (end == 0) return false;  // the null record ending a list
  node.name = d.substr(at, name_length);
  at += name_length;
  for (uint64_t p = 0; p < properties; ++p) {
    const char type = take<char>(d, at);
    switch (type) {
      case 'Y':
        node.numbers.push_back(take<int16_t>(d, at));
        break;
      case 'C':
        node.numbers.push_back(take<uint8_t>(d, at));
        break;
      case 'I':
        node.numbers.push_back(take<int32_t>(d, at));
        break;
      case 'F':
        node.numbers.push_back(take<float>(d, at));
        break;
      case 'D':
        node.numbers.push_back(take<double>(d, at));
        break;
      case 'L':
        node.numbers.push_back(double(take<int64_t>(d, at)));
        break;
      case 'S':
      case 'R': {
        const uint32_t length = take<uint32_t>(d, at);
        if (type == 'S') node.strings.push_back(d.substr(at, length));
        at += length;
        break;
      }
      default: {  // arrays: length, encoding, bytes
        const uint32_t length = take<uint32_t>(d, at), encoding = take<uint32_t>(d, at),
                       bytes = take<uint32_t>(d, at);
        if (encoding != 0) throw std::runtime_error("a compressed array");
        for (uint32_t k = 0; k < length && type == 'l'; ++k)
          node.longs.push_back(take<int64_t>(d, at));
        for (uint32_t k = 0; k < length && type == 'f'; ++k)
          node.floats.push_back(take<float>(d, at));
        if (type != 'l' && type != 'f') at += bytes;
      }
    }
  }
  while (at < end) {
    FbxNode child;
    if (!readNode(d, at, child)) break;
    node.children.push_back(std::move(child));
  }
  at = end;
  return true;
}

TEST(FbxExport, BinaryHoldsTheSameSkeletonSkinAndTakeForBlender) {
  const SkinnedMesh body = testing::makeHumanMesh();
  const MotionClip clip = testClip(body.skeleton);
  const std::filesystem::path dir = testFolder("fbx_export_binary");
  saveAnimatedBodyFbx(body, clip, dir / "actor.fbx");
  const std::string d = readFile(dir / "actor.fbx");
  ASSERT_GT(d.size(), 27u);
  EXPECT_EQ(d.substr(0, 23), std::string("Kaydara FBX Binary  \0\x1a\0", 23));
  size_t at = 23;
  EXPECT_EQ(take<uint32_t>(d, at), 7500u);  // FBX 7.5, what Blender 2.8+ reads
  FbxNode file;
  while (at < d.size()) {
    FbxNode node;
    if (!readNode(d, at, node)) break;
    file.children.push_back(std::move(node));
  }
  // The joints as skeleton nodes (LimbNode), the body as a mesh, a skin cluster per joint.
  std::vector<const FbxNode*> models, clusters, stacks, curves;
  file.collect("Model", models);
  file.collect("Deformer", clusters);
  file.collect("AnimationStack", stacks);
  file.collect("AnimationCurve", curves);
  std::map<std::string, std::string> types;  // model name: type
  for (const FbxNode* model : models) {
    ASSERT_EQ(model->strings.size(), 2u);
    types[model->strings[0].substr(0, model->strings[0].find('\0'))] = model->strings[1];
  }
  for (const Joint& joint : body.skeleton.joints()) EXPECT_EQ(types[joint.name], "LimbNode");
  EXPECT_EQ(types["body"], "Mesh");
  int skin_clusters = 0;
  for (const FbxNode* deformer : clusters) skin_clusters += deformer->strings.at(1) == "Cluster";
  EXPECT_EQ(skin_clusters, body.skeleton.jointCount());
  ASSERT_EQ(stacks.size(), 1u);
  EXPECT_EQ(stacks[0]->strings.at(0).substr(0, 4), "walk");
  // A translation, rotation and scale curve on each axis of each joint, a key per frame at the
  // clip's times (FBX time: 46186158000 a second).
  EXPECT_EQ(int(curves.size()), 9 * body.skeleton.jointCount());
  for (const FbxNode* curve : curves) {
    std::vector<const FbxNode*> times;
    curve->collect("KeyTime", times);
    ASSERT_EQ(times.size(), 1u);
    ASSERT_EQ(int(times[0]->longs.size()), kFrames);
    for (int f = 0; f < kFrames; ++f)
      EXPECT_NEAR(double(times[0]->longs[f]), f / kFps * 46186158000.0, 1e3);
  }
  // The capture's rate (30 fps: TimeMode 6) and length on the timeline and the take, not
  // Assimp's 24 fps and one second.
  std::map<std::string, std::vector<double>> settings;  // P record name: its numbers
  std::vector<const FbxNode*> records;
  file.collect("P", records);
  for (const FbxNode* p : records) {
    if (!p->strings.empty()) settings[p->strings[0]] = p->numbers;  // the last record of a name
  }
  const double stop = std::floor((kFrames - 1) / kFps * 46186158000.0);
  EXPECT_EQ(settings["TimeMode"], std::vector<double>{6});
  EXPECT_EQ(settings["CustomFrameRate"], std::vector<double>{kFps});
  EXPECT_EQ(settings["TimeSpanStop"], std::vector<double>{stop});
  EXPECT_EQ(settings["LocalStop"], std::vector<double>{stop});  // the take's, after the template's
  EXPECT_EQ(settings["ReferenceStop"], std::vector<double>{stop});
  // The same scene as the ASCII file that reads back: the curves' values agree.
  saveAnimatedBodyFbx(body, clip, dir / "ascii.fbx", 1, FbxEncoding::kAscii);
  const std::string ascii = readFile(dir / "ascii.fbx");
  EXPECT_NE(ascii.find("KeyValueFloat: *" + std::to_string(kFrames)), std::string::npos);
}

TEST(FbxExport, RefusesWhatItCannotWriteByName) {
  const SkinnedMesh body = testing::makeHumanMesh();
  MotionClip clip = testClip(body.skeleton);
  const std::filesystem::path dir = testFolder("fbx_export_errors");
  clip.frames[3].angles_rad.pop_back();
  EXPECT_NE(errorOf([&] {
              saveAnimatedBodyFbx(body, clip, dir / "a.fbx");
            }).find("a.fbx: frame 3 of the motion poses"),
            std::string::npos);
  clip.frames.clear();
  EXPECT_NE(errorOf([&] { saveAnimatedBodyFbx(body, clip, dir / "a.fbx"); }).find("no frame"),
            std::string::npos);
  const std::string missing = (dir / "missing" / "a.fbx").string();
  EXPECT_EQ(errorOf([&] {
              saveAnimatedBodyFbx(body, testClip(body.skeleton), missing);
            }).find(missing + ": FBX export failed"),
            0u);
  EXPECT_FALSE(std::filesystem::exists(dir / "a.fbx"));
}

}  // namespace
}  // namespace lumistage
