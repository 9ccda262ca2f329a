#include "core/body/fbx_export.h"

#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/assimp_scene.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// FBX's unit is the centimetre (Assimp writes UnitScaleFactor 1): Blender, Maya and Unity scale
// by it, so positions in metres would stand a body 1.7 cm tall.
constexpr double kCentimetres = 100;

// A key per frame on every joint: its local translation (the rest offset; the root's moves) and
// rotation in the file's axes, scale 1.
aiAnimation* animation(const Skeleton& skeleton, const MotionClip& clip, const Eigen::Matrix3d& c,
                       double s) {
  auto* a = new aiAnimation;
  a->mName = clip.name.empty() ? "take" : clip.name;
  // Assimp 5.2's FBX exporter takes key times in seconds, whatever mTicksPerSecond says, and
  // writes the take's end as whole seconds, mDuration / mTicksPerSecond rounded down: 1 tick a
  // second, the duration rounded up (not 0, so that setFbxTiming finds it and sets it exactly).
  a->mTicksPerSecond = 1;
  a->mDuration = std::max(1.0, std::ceil(double(clip.frames.size() - 1) / clip.fps));
  const int joints = skeleton.jointCount();
  const unsigned frames = unsigned(clip.frames.size());
  a->mNumChannels = unsigned(joints);
  a->mChannels = new aiNodeAnim*[joints];
  for (int j = 0; j < joints; ++j) {
    auto* channel = new aiNodeAnim;
    channel->mNodeName = skeleton.joint(j).name;
    channel->mNumPositionKeys = channel->mNumRotationKeys = channel->mNumScalingKeys = frames;
    channel->mPositionKeys = new aiVectorKey[frames];
    channel->mRotationKeys = new aiQuatKey[frames];
    channel->mScalingKeys = new aiVectorKey[frames];
    for (unsigned f = 0; f < frames; ++f) {
      const Pose& pose = clip.frames[f];
      const Eigen::Vector3d angles = pose.angles_rad[size_t(j)];
      Eigen::Matrix3d r;
      Eigen::Vector3d t = skeleton.joint(j).offset_m;
      if (j == 0) {
        const double angle = angles.norm();
        r = angle > 0 ? Eigen::AngleAxisd(angle, angles / angle).toRotationMatrix()
                      : Eigen::Matrix3d::Identity();
        t += pose.root_translation_m;
      } else {
        r = eulerRotation(angles);
      }
      const Eigen::Quaterniond q(c * r * c);  // c is its own inverse
      const double time = f / clip.fps;
      channel->mPositionKeys[f] = aiVectorKey(time, toAi(s * (c * t)));
      channel->mRotationKeys[f] =
          aiQuatKey(time, aiQuaternion(float(q.w()), float(q.x()), float(q.y()), float(q.z())));
      channel->mScalingKeys[f] = aiVectorKey(time, aiVector3D(1, 1, 1));
    }
    a->mChannels[j] = channel;
  }
  return a;
}

// FBX time: 46186158000 ticks a second. Assimp writes a key at int64(seconds * that).
constexpr int64_t kFbxSecond = 46186158000;

// FBX's TimeMode for a frame rate: the standard one where there is one, else 14 (custom, the rate
// in CustomFrameRate).
int fbxTimeMode(double fps) {
  const std::pair<double, int> modes[] = {{120, 1}, {100, 2}, {60, 3},  {50, 4},
                                          {48, 5},  {30, 6},  {25, 10}, {24, 11}};
  for (const auto& [rate, mode] : modes)
    if (std::abs(fps - rate) < 1e-9) return mode;
  return 14;
}

// A binary FBX property record's head: its name, type, label and flags as 'S' strings, then the
// value's type code.
std::string binaryProperty(const std::string& name, const std::string& type,
                           const std::string& label, char code) {
  std::string head;
  for (const std::string* text : {&name, &type, &label}) {
    const uint32_t length = uint32_t(text->size());
    head += 'S';
    head.append(reinterpret_cast<const char*>(&length), 4);
    head += *text;
  }
  head += std::string("S\0\0\0\0", 5);
  head += code;
  return head;
}

// Sets a property's value in every record of it (a KTime left 0, the templates', stays 0).
template <typename T>
int setBinaryProperty(std::string& data, const std::string& head, T value, bool keep_zero) {
  int set = 0;
  for (size_t at = data.find(head); at != std::string::npos; at = data.find(head, at + 1)) {
    const size_t where = at + head.size();
    if (where + sizeof(T) > data.size()) break;
    T old{};
    std::memcpy(&old, data.data() + where, sizeof(T));
    if (keep_zero && old == T{}) continue;
    std::memcpy(data.data() + where, &value, sizeof(T));
    ++set;
  }
  return set;
}

// The same in an ASCII file: the value after `P: "NAME", ...,`.
int setAsciiProperty(std::string& data, const std::string& name, const std::string& value,
                     bool keep_zero) {
  int set = 0;
  const std::string head = "P: \"" + name + "\", ";
  for (size_t at = data.find(head); at != std::string::npos; at = data.find(head, at + 1)) {
    const size_t end = data.find('\n', at);
    const size_t comma = data.rfind(',', end);
    if (end == std::string::npos || comma == std::string::npos || comma < at) break;
    const size_t start = comma + 2;
    if (keep_zero && data.compare(start, end - start, "0") == 0) continue;
    data.replace(start, end - start, value);
    ++set;
  }
  return set;
}

// Assimp 5.2's FBX exporter writes 24 fps and a one-second timeline whatever the take: the
// file's rate (TimeMode, CustomFrameRate), timeline (TimeSpanStop) and the take's end (LocalStop,
// ReferenceStop) are set to the clip's, so that Blender and Maya open it at the capture's rate
// and length. Returns how many of the five were found.
int setFbxTiming(std::string& data, double fps, int64_t stop, FbxEncoding encoding) {
  const int mode = fbxTimeMode(fps);
  if (encoding == FbxEncoding::kAscii) {
    return setAsciiProperty(data, "TimeMode", std::to_string(mode), false) +
           setAsciiProperty(data, "CustomFrameRate", fmt::format("{}", fps), false) +
           setAsciiProperty(data, "TimeSpanStop", std::to_string(stop), false) +
           setAsciiProperty(data, "LocalStop", std::to_string(stop), true) +
           setAsciiProperty(data, "ReferenceStop", std::to_string(stop), true);
  }
  return setBinaryProperty(data, binaryProperty("TimeMode", "enum", "", 'I'), int32_t(mode),
                           false) +
         setBinaryProperty(data, binaryProperty("CustomFrameRate", "double", "Number", 'D'), fps,
                           false) +
         setBinaryProperty(data, binaryProperty("TimeSpanStop", "KTime", "Time", 'L'), stop,
                           false) +
         setBinaryProperty(data, binaryProperty("LocalStop", "KTime", "Time", 'L'), stop, true) +
         setBinaryProperty(data, binaryProperty("ReferenceStop", "KTime", "Time", 'L'), stop, true);
}

std::unique_ptr<aiScene> buildScene(const SkinnedMesh& body, const MotionClip& clip, double scale) {
  const Eigen::Matrix3d c = yUpToOurs();  // its own inverse: ours to the file's too
  const double s = kCentimetres * scale;
  auto scene = std::make_unique<aiScene>();
  aiNode* root = scene->mRootNode = new aiNode("lumistage_actor");
  const std::vector<aiNode*> joints = skeletonNodes(body.skeleton, c, s, root);
  auto* mesh_node = new aiNode("body");
  mesh_node->mParent = root;
  mesh_node->mNumMeshes = 1;
  mesh_node->mMeshes = new unsigned[1]{0};
  root->mNumChildren = 2;
  root->mChildren = new aiNode* [2] { joints[0], mesh_node };

  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial* [1] { new aiMaterial };
  const aiString material_name("lumistage_skin");
  scene->mMaterials[0]->AddProperty(&material_name, AI_MATKEY_NAME);
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh* [1] { skinnedAiMesh(body, "body", c, s) };
  scene->mNumAnimations = 1;
  scene->mAnimations = new aiAnimation* [1] { animation(body.skeleton, clip, c, s) };
  return scene;
}

}  // namespace

void saveAnimatedBodyFbx(const SkinnedMesh& body, const MotionClip& clip, const fs::path& file,
                         double scale, FbxEncoding encoding) {
  const std::string name = file.string();
  try {
    body.validate();
  } catch (const std::invalid_argument& e) {
    throw Error(name + ": cannot write the body: " + e.what());
  }
  const int joints = body.skeleton.jointCount();
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    if (clip.frames[f].angles_rad.size() != size_t(joints))
      throw Error(name + ": frame " + std::to_string(f) + " of the motion poses " +
                  std::to_string(clip.frames[f].angles_rad.size()) + " joints, the body has " +
                  std::to_string(joints));
  }
  if (clip.frames.empty()) throw Error(name + ": no frame of motion to write");
  if (!(clip.fps > 0)) throw Error(name + ": the motion has no frame rate");
  if (!(scale > 0)) throw Error(name + ": the body's scale must be above 0");
  const std::unique_ptr<aiScene> scene = buildScene(body, clip, scale);
  // Written beside its name, its timing set, then written whole under its name: an export cut
  // short leaves nothing there.
  const fs::path partial = file.parent_path() / (file.stem().string() + ".partial.fbx");
  Assimp::Exporter exporter;
  const char* format = encoding == FbxEncoding::kBinary ? "fbx" : "fbxa";
  if (exporter.Export(scene.get(), format, partial.string()) != AI_SUCCESS) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw Error(name + ": FBX export failed: " + exporter.GetErrorString());
  }
  std::string data;
  try {
    data = readFile(partial);
  } catch (const Error&) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw;
  }
  std::error_code ignored;
  fs::remove(partial, ignored);
  const int64_t stop = int64_t(double(clip.frames.size() - 1) / clip.fps * double(kFbxSecond));
  if (setFbxTiming(data, clip.fps, stop, encoding) < 5)
    throw Error(name + ": FBX export failed: Assimp's file lacks the timing this writer sets");
  writeFileAtomically(file, data, {.sync = false});
}

}  // namespace lumistage
