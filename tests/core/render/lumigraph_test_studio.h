#pragma once

// The lumigraph renderer's tests' scene: one frame of the reference studio, and what they count.

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <vector>

#include "core/render/lumigraph_renderer.h"
#include "core/sim/virtual_studio.h"

namespace lumistage::testing {

// One frame of the reference studio (12 cameras, 1024x768), rendered once for every test.
class LumigraphRendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    StudioConfig config = loadStudioConfig(std::filesystem::path(LUMISTAGE_TEST_RESOURCE_DIR) /
                                           "studio" / "reference.yaml");
    studio_ = new VirtualStudio(config, 12);
    frame_ = new StudioFrame;
    studio_->renderFrame(10, *frame_);
    frame_->surface.computeNormals();
  }
  static void TearDownTestSuite() {
    delete frame_;
    delete studio_;
  }
  const Rig& rig() const { return studio_->rig(); }
  // A renderer of `own` cameras (all when empty) with the frame's surface and images.
  std::unique_ptr<LumigraphRenderer> makeRenderer(std::vector<int> own = {},
                                                  const LumigraphParams& params = {}) const {
    if (own.empty())
      for (int c = 0; c < rig().cameraCount(); ++c) own.push_back(c);
    auto r = std::make_unique<LumigraphRenderer>(rig(), own, params);
    r->setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (size_t j = 0; j < own.size(); ++j) {
      const Camera& c = rig().camera(own[j]);
      r->setImageRgba(static_cast<int>(j), frame_->images[own[j]].data(), c.width(), c.height());
    }
    return r;
  }
  // A virtual camera between cameras 0 and 1 (not on any input camera), smaller.
  Camera desiredView() const {
    const Camera& a = rig().camera(0);
    const Camera& b = rig().camera(1);
    return lookingAtTheActor(0.5 * (a.centre() + b.centre()));
  }
  // A virtual camera at `centre` looking at the middle of the stage, a metre up.
  static Camera lookingAtTheActor(const Eigen::Vector3d& centre) {
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 1.0) - centre).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    Eigen::Matrix3d R;
    R.row(0) = x;
    R.row(1) = z.cross(x);
    R.row(2) = z;
    return Camera("desired", 480, 360, {400, 400, 239.5, 179.5, 0}, {}, R, -R * centre);
  }
  static inline VirtualStudio* studio_ = nullptr;
  static inline StudioFrame* frame_ = nullptr;
};

inline int64_t covered(const std::vector<uint8_t>& rgba) {
  int64_t n = 0;
  for (size_t i = 3; i < rgba.size(); i += 4) n += rgba[i] > 0;
  return n;
}

}  // namespace lumistage::testing
