// Markerless motion capture from low-resolution silhouettes, against the actor's true joints.
#include "core/tracking/pose_tracker.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/body/motion_library.h"
#include "tests/core/tracking/synthetic_stage.h"

namespace lumistage {
namespace {

using testing::mpjpe;
using testing::SyntheticStage;

const std::string kStudio = std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/studio/reference.yaml";

const SkinnedMesh& generic() {
  static const SkinnedMesh mesh = makeHumanModel({});
  return mesh;
}

struct ClipErrors {
  double mean_m = 0, max_m = 0;
  int tracked = 0, frames = 0;
};

ClipErrors trackClip(SyntheticStage& stage, PoseTracker& tracker, const std::string& clip_name,
                     int frames, int stride, const std::vector<int>& cameras = {}) {
  const MotionClip clip = makeBuiltinClip(clip_name, stage.actor.skeleton, 30.0, frames / 30.0 + 1);
  ClipErrors e;
  for (int f = 0; f < frames; f += stride) {
    const TrackResult& r = tracker.track(stage.render(clip.sample(f / 30.0), cameras));
    ++e.frames;
    if (!r.valid()) continue;
    const double err = mpjpe(r.joints, stage.joints);
    if (getenv("LUMISTAGE_TRACKER_VERBOSE"))
      std::printf("%s frame %d: %.1f mm, rms %.1f mm, %d hull\n", clip_name.c_str(), f, err * 1e3,
                  r.fit_rms_m * 1e3, r.hull_points);
    ++e.tracked;
    e.mean_m += err;
    e.max_m = std::max(e.max_m, err);
  }
  if (e.tracked) e.mean_m /= e.tracked;
  return e;
}

TEST(PoseTracker, TracksEveryClipOfTheReferenceActor) {
  SyntheticStage stage(kStudio);
  for (const char* clip : {"walk", "arm_wave", "turn", "crouch"}) {
    PoseTracker tracker(stage.config.rig, generic());
    const ClipErrors e = trackClip(stage, tracker, clip, 60, 1);
    std::printf("%s: mean %.1f mm, max %.1f mm, %d/%d frames, height %.3f\n", clip, e.mean_m * 1e3,
                e.max_m * 1e3, e.tracked, e.frames, tracker.shape().height_m);
    EXPECT_EQ(e.tracked, e.frames) << clip;
    EXPECT_LT(e.mean_m, 0.025) << clip;
    EXPECT_LT(e.max_m, 0.080) << clip;
  }
}

TEST(PoseTracker, DiagTPose) {
  SyntheticStage stage(kStudio);
  PoseTracker tracker(stage.config.rig, generic());
  if (getenv("TRUE_SHAPE")) tracker.setShape(stage.config.actor.shape);
  const MotionClip clip = makeBuiltinClip("walk", stage.actor.skeleton, 30.0, 2);
  const TrackResult& r = tracker.track(stage.render(clip.sample(0)));
  const BodyShape& s = tracker.shape();
  std::printf("shape h %.3f arm %.3f leg %.3f sh %.3f hip %.3f girth %.3f\n", s.height_m,
              s.arm_length_scale, s.leg_length_scale, s.shoulder_width_scale, s.hip_width_scale,
              s.girth_scale);
  for (int j = 0; j < kHumanJointCount; ++j) {
    const Eigen::Vector3d d = r.joints[j] - stage.joints[j];
    std::printf("%-16s err %6.1f mm  (%6.1f %6.1f %6.1f)\n",
                stage.actor.skeleton.joint(j).name.c_str(), d.norm() * 1e3, d.x() * 1e3,
                d.y() * 1e3, d.z() * 1e3);
  }
}
}  // namespace
}  // namespace lumistage
