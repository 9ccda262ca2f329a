#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lumistage {

// One camera of a wand session: its name (as in the rig) and image size.
struct WandCamera {
  std::string name;
  int width = 0;
  int height = 0;
};

// A sample whose world position is known: the wand's point held on a floor mark. Three or more
// fix the floor, the heading and (without a wand length) the scale.
struct FloorMark {
  int sample = 0;
  Eigen::Vector3d world_m = Eigen::Vector3d::Zero();
};

// The correspondence table of a wand session: what each camera saw of each sample (one instant
// of the wand's bright point), missing where a camera did not see it or its detector rejected
// the frame. File format: docs/calibration.md.
class WandSession {
 public:
  WandSession() = default;
  WandSession(std::vector<WandCamera> cameras, int samples);

  const std::vector<WandCamera>& cameras() const { return cameras_; }
  int cameraCount() const { return static_cast<int>(cameras_.size()); }
  int sampleCount() const { return samples_; }
  std::optional<int> findCamera(std::string_view name) const;

  // Adds samples at the end; returns the index of the first one.
  int addSamples(int count);
  void set(int sample, int camera, const Eigen::Vector2d& pixel);
  void clear(int sample, int camera);
  bool has(int sample, int camera) const { return seen_[index(sample, camera)] != 0; }
  const Eigen::Vector2d& pixel(int sample, int camera) const {
    return pixels_[index(sample, camera)];
  }
  int observationCount(int camera) const;  // samples the camera saw
  int viewCount(int sample) const;         // cameras that saw the sample

  // Pairs of samples at the two ends of a rigid wand (an LED at each end, lit in turn), whose
  // distance is the wand length given to the solver.
  std::vector<std::pair<int, int>> wand_pairs;
  std::vector<FloorMark> floor_marks;

 private:
  size_t index(int sample, int camera) const {
    return static_cast<size_t>(sample) * cameras_.size() + static_cast<size_t>(camera);
  }
  std::vector<WandCamera> cameras_;
  int samples_ = 0;
  std::vector<Eigen::Vector2d> pixels_;
  std::vector<uint8_t> seen_;
};

// Text file (docs/calibration.md). Throws Error naming file:line and what was expected.
WandSession loadWandSession(const std::filesystem::path& path);
WandSession parseWandSession(std::string_view text, std::string_view source_name);
std::string formatWandSession(const WandSession& session);
void saveWandSession(const WandSession& session, const std::filesystem::path& path);  // atomic

}  // namespace lumistage
