#include "core/refine/frame_refiner.h"

#include <string>

#include "core/base/error.h"

namespace lumistage {

FrameRefiner::FrameRefiner(const Rig& rig, const RefineConfig& config, int vertex_count,
                           const std::vector<Eigen::Vector3i>& triangles)
    : rig_(rig),
      config_(config),
      triangles_(triangles),
      sampler_(config),
      refiner_(config, vertex_count, triangles),
      keyers_(rig.cameraCount()),
      mask_keys_(rig.cameraCount()) {}

void FrameRefiner::refine(const std::vector<CameraFrame>& frames, const Eigen::Matrix3Xf& positions,
                          const Eigen::Matrix3Xf& normals, Eigen::Matrix3Xf& refined,
                          int left_out) {
  if (!keyers_learnt_) {
    for (int c = 0; c < rig_.cameraCount(); ++c) keyers_[c].learnScreen(frames[c].image.view());
    keyers_learnt_ = true;
  }
  combined_.reset(config_.pointsPerVertex() * int(positions.cols()), config_.offset_count,
                  config_.colour_bits);
  wire_bytes_ = 0;
  for (const RigNode& node : rig_.nodes()) {
    inputs_.clear();
    for (int c : node.cameras) {
      if (c == left_out) continue;
      const CameraFrame& frame = frames[c];
      const ImageView image = frame.image.view();
      SamplerCamera input{&rig_.camera(c), image, &keyers_[c], nullptr, nullptr};
      if (!frame.mask.empty()) {
        mask_keys_[c] =
            MaskKey(frame.mask.data(), image.width, image.height, isBayer(image.format));
        input.green_screen = nullptr;
        input.mask = &mask_keys_[c];
      } else if (size_t(c) < plates_.size() && plates_[c]) {
        input.green_screen = nullptr;
        input.background = plates_[c].get();
      }
      inputs_.push_back(input);
    }
    // The visibility from the surface the last frame refined to, as the pipeline's nodes do.
    sampler_.sample(inputs_, positions, normals, triangles_, node_stats_, offsets_);
    codec_.encode(node_stats_, wire_);
    wire_bytes_ += wire_.size();
    if (const Status added = codec_.add(wire_, combined_); !added.ok())
      throw Error("refinement: node " + node.name + ": " + added.error());
  }
  combined_.dropOutside();
  refiner_.refine(combined_, offsets_);
  applyOffsets(config_, offsets_, positions, normals, refined);
}

}  // namespace lumistage
