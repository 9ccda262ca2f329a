#pragma once

// The refinement's tests' scene as a test fixture: the textured ellipsoid of refine_test_scene.h
// filmed once for all of a suite's tests by a small ring, with the error of a mesh against it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/imaging/keyer.h"
#include "core/refine/refinement_sampler.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage::testing {

class EllipsoidScene : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    rig_ = new Rig(testing::smallRing());
    images_ = new std::vector<Image>(testing::renderEllipsoid(*rig_, shape_));
  }
  static void TearDownTestSuite() {
    delete rig_;
    delete images_;
  }
  std::vector<SamplerCamera> cameras(const std::vector<int>& which) const {
    std::vector<SamplerCamera> out;
    for (int c : which) out.push_back({&rig_->camera(c), (*images_)[c].view(), &keyer_, nullptr});
    return out;
  }
  // Mean and largest distance of the mesh's vertices from the ellipsoid, along the rays from the
  // centre (the ellipsoid is nearly a sphere: close to the true distance).
  static std::pair<double, double> error(const Eigen::Matrix3Xf& positions) {
    double sum = 0, worst = 0;
    for (Eigen::Index v = 0; v < positions.cols(); ++v) {
      const Eigen::Vector3d d = positions.col(v).cast<double>() - shape_.centre;
      const double e = std::abs(d.norm() - shape_.radiusAlong(d.normalized()));
      sum += e;
      worst = std::max(worst, e);
    }
    return {sum / double(positions.cols()), worst};
  }
  static inline testing::Ellipsoid shape_;
  static inline Rig* rig_ = nullptr;
  static inline std::vector<Image>* images_ = nullptr;
  GreenScreenKeyer keyer_;
};

}  // namespace lumistage::testing
