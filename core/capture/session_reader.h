#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/capture/image.h"
#include "core/capture/image_files.h"
#include "core/geometry/rig.h"

namespace lumistage {

// Reads a recorded session (docs/session-format.md). Opening checks session.yaml, rig.yaml and
// index.csv strictly and every listed frame's image files cheaply (present; a PNG's header of the
// right size and channels, complete to its last chunk; a PNM's header, and every pixel there). A
// crash or a full disk only ever cuts a session short: the readable session ends before the first
// frame that is torn or incomplete, and warnings() says which and why. Anything else malformed is
// an Error naming file:line.
class SessionReader {
 public:
  explicit SessionReader(const std::filesystem::path& folder);

  const std::filesystem::path& folder() const { return folder_; }
  const Rig& rig() const { return rig_; }
  PixelFormat pixelFormat() const { return format_; }
  ImageFiles imageFiles() const { return files_; }
  double fps() const { return fps_; }
  const std::string& source() const { return source_; }
  bool hasTruth() const { return truth_; }

  // The readable frames, in recording order.
  int frameCount() const { return static_cast<int>(frames_.size()); }
  int64_t frameId(int i) const { return frames_.at(i).id; }
  int64_t timestampNs(int i) const { return frames_.at(i).timestamp_ns; }
  // Why the readable session is shorter than what was recorded, or what was left over: one
  // message per problem, naming the file and the frame. Empty for a cleanly closed session.
  const std::vector<std::string>& warnings() const { return warnings_; }

  // Decodes frame i, one CameraFrame per camera of the rig (index order), reusing `out`'s image
  // buffers. Throws Error naming the file when an image cannot be decoded (damaged after open).
  // `cameras`: only these rig cameras are decoded (a node reads its own); empty: all. `out` is
  // indexed by rig camera either way.
  void readFrame(int i, std::vector<CameraFrame>& out, const std::vector<int>& cameras = {}) const;
  std::filesystem::path imagePath(int camera, int i) const;

  // Ground truth (virtual studio sessions, hasTruth()). Joints per readable frame, in the order
  // of truth/joints.csv's header (names in `joint_names` when given). Throws Error naming
  // file:line for a malformed line or a frame without joints.
  std::vector<std::vector<Eigen::Vector3d>> readTruthJoints(
      std::vector<std::string>* joint_names = nullptr) const;
  std::filesystem::path truthMaskPath(int camera, int i) const;
  // Camera `camera`'s truth mask at frame i: one byte a pixel, non-zero on the actor, of the
  // camera's size. Throws Error naming the file when it is missing or of another size.
  std::vector<uint8_t> readTruthMask(int camera, int i) const;

  // The empty stage, filmed before the take by every camera (a stage without a green screen is
  // keyed on it: BackgroundModel): plate/<camera>/000000.png ... in the session's format and image
  // files (SessionWriter::writePlate). The plate's frames of camera `camera`: 0 without.
  int plateFrames(int camera) const;
  std::filesystem::path platePath(int camera, int i) const;
  // Throws Error naming the file when it is missing, unreadable or of another size.
  Image readPlate(int camera, int i) const;

  // Masks another tool made of the actor (a matting tool, a segmenter): masks/<camera>/<frame
  // id>.png, one byte a pixel, non-zero on the actor, of the camera's size. A session carries them
  // when its folder has masks/ (lumistage session import --masks); they then stand for the key.
  bool hasMasks() const;
  std::filesystem::path maskPath(int camera, int i) const;
  // Throws Error naming the file when it is missing, unreadable or of another size.
  std::vector<uint8_t> readMask(int camera, int i) const;
  // The masks as the other tool made them, where `lumistage session masks` repaired masks/ from a
  // clean plate of the take (docs/session-format.md): masks-given/<camera>/<frame id>.png, kept as
  // they came. Without masks-given/ (never repaired), masks/ holds them. Nothing else reads them.
  bool hasRepairedMasks() const;
  std::filesystem::path givenMaskPath(int camera, int i) const;
  // Throws Error naming the file when it is missing, unreadable or of another size.
  std::vector<uint8_t> readGivenMask(int camera, int i) const;
  // Frame i's masks into `out[c].mask` (indexed by rig camera, as readFrame; only `cameras`, or
  // all), reusing their buffers. A camera whose mask is missing, unreadable or of another size gets
  // an empty mask and, in `errors[c]`, why, naming the file; the others' are read.
  void readMasks(int i, std::vector<CameraFrame>& out, std::vector<std::string>& errors,
                 const std::vector<int>& cameras = {}) const;

 private:
  struct FrameEntry {
    int64_t id;
    int64_t timestamp_ns;
  };
  void readSessionYaml();
  void readIndex();
  void checkImages();

  std::filesystem::path folder_;
  Rig rig_;
  PixelFormat format_ = PixelFormat::kMono8;
  ImageFiles files_ = ImageFiles::kPng;
  double fps_ = 0;
  std::string source_;
  bool truth_ = false;
  std::vector<FrameEntry> frames_;
  std::vector<std::string> warnings_;
};

}  // namespace lumistage
