#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/geometry/rig.h"

namespace lumistage {

// Pixel layouts a session stores. Bayer is what GigE Vision cameras deliver: one byte a pixel.
enum class PixelFormat { kRgb8, kBayerRggb8 };
const char* pixelFormatName(PixelFormat format);  // "rgb8", "bayer_rggb8"

// Ground truth of one frame of the virtual studio.
struct FrameTruth {
  std::vector<Eigen::Vector3d> joints;    // metres, in the skeleton's joint order
  const TriangleMesh* surface = nullptr;  // posed actor surface (positions, triangles)
  const std::vector<std::vector<uint8_t>>* masks = nullptr;  // per camera, 255 = actor
};

// Writes a recorded session in the layout of docs/session-format.md. Every file is written
// beside its place and renamed into it; a frame's line goes into index.csv only once all of its
// files are complete, so a crash never leaves a frame that the index promises but the disk lacks.
class SessionWriter {
 public:
  // Creates `folder` (which must not exist, or be empty) and writes session.yaml and rig.yaml.
  // Throws Error naming the folder and the reason.
  SessionWriter(const std::filesystem::path& folder, const Rig& rig, PixelFormat format, double fps,
                const std::string& source, const std::vector<std::string>& joint_names = {});
  ~SessionWriter();

  // One frame: per camera an image, RGBA8 (alpha ignored) of the camera's size, rows top first.
  // Converted to the session's pixel format. Throws Error on a write failure.
  void writeFrame(int64_t frame_id, int64_t timestamp_ns, const std::vector<const uint8_t*>& rgba,
                  const FrameTruth* truth = nullptr);
  int framesWritten() const { return frames_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  std::filesystem::path folder_;
  Rig rig_;
  PixelFormat format_;
  std::vector<std::string> joint_names_;
  std::ofstream index_;
  std::ofstream joints_;
  int frames_ = 0;
};

// Converts RGBA8 to Bayer RGGB8: even rows R G R G..., odd rows G B G B...
void rgbaToBayerRggb(const uint8_t* rgba, int width, int height, uint8_t* bayer);

}  // namespace lumistage
