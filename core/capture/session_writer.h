#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/body/skinned_mesh.h"
#include "core/capture/image.h"
#include "core/capture/image_files.h"
#include "core/geometry/rig.h"

namespace lumistage {

// Writes `image` as a PNG file (rgb8 in colour, any other format one byte a pixel), encoded in
// memory and written with checked system calls beside its place, then renamed into it:
// cv::imwrite ignores the result of fclose, so on a full disk it could leave a truncated PNG.
// Throws Error naming the file. Returns the bytes written.
size_t writePngAtomically(const std::filesystem::path& path, const ImageView& image);

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
                const std::string& source, const std::vector<std::string>& joint_names = {},
                ImageFiles files = ImageFiles::kPng);
  ~SessionWriter();

  // One frame: per camera an image of the camera's size in the session's pixel format. Throws
  // Error naming the file on a write failure (disk full...), or on a wrong size or format; the
  // frame is then not in the index and the session stays valid.
  void writeFrame(int64_t frame_id, int64_t timestamp_ns, const std::vector<ImageView>& images,
                  const FrameTruth* truth = nullptr);
  // One frame from image files of another session in this one's pixel format and image files, one
  // per camera of the camera's size (as its SessionReader checked them on opening): copied byte
  // for byte, written as writeFrame writes (beside their place, renamed in, then the index line).
  // Joins sessions without decoding and encoding again. Throws Error naming the file as
  // writeFrame does. `truth` as writeFrame's.
  void copyFrame(int64_t frame_id, int64_t timestamp_ns,
                 const std::vector<std::filesystem::path>& files,
                 const FrameTruth* truth = nullptr);
  // Frame `index` (from 0) of the empty stage, one image per camera as writeFrame's, into
  // plate/<camera>/: the clean plate a stage without a green screen is keyed on (SessionReader::
  // plateFrames). Not a frame of the session: no index line. Throws Error as writeFrame does.
  void writePlate(int index, const std::vector<ImageView>& images);
  int framesWritten() const { return frames_; }
  int64_t bytesWritten() const { return bytes_; }  // camera images' file bytes of indexed frames
  ImageFiles imageFiles() const { return files_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  // Throws Error naming `what` (a frame, a plate frame) unless `images` are one per camera of the
  // camera's size in the session's format.
  void checkImages(const std::string& what, const std::vector<ImageView>& images) const;
  // One image in the session's image files; the bytes written.
  size_t writeImage(const std::filesystem::path& path, const ImageView& view) const;
  // Last of a frame: its index line (it exists for readers only once this is complete).
  void appendIndex(int64_t frame_id, int64_t timestamp_ns, int64_t bytes);
  // A frame's truth: its masks (unless written already), surface and joints' line.
  void writeTruth(int64_t frame_id, const FrameTruth& truth, bool masks);

  std::filesystem::path folder_;
  Rig rig_;
  PixelFormat format_;
  ImageFiles files_;
  std::vector<std::string> joint_names_;
  AppendOnlyFile index_;
  AppendOnlyFile joints_;
  int frames_ = 0;
  int64_t bytes_ = 0;
};

}  // namespace lumistage
