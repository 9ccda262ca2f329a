#include "core/calib/wand_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/calib/similarity.h"
#include "core/calib/wand_detector.h"
#include "core/calib/wand_simulation.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

// The reference rig: 12 cameras at 1024x768 around a 3x3 m stage, barrel distortion.
Rig referenceRig() {
  return makeRingRig(RingRigSpec{});
}

// Where a camera saw the wand (outliers left out).
std::vector<Eigen::Vector2d> seenPixels(const SimulatedWandSession& s, const std::string& camera) {
  const int c = *s.session.findCamera(camera);
  std::vector<Eigen::Vector2d> pixels;
  for (int sp = 0; sp < s.session.sampleCount(); ++sp) {
    if (s.session.has(sp, c) && !s.outlier[sp][c]) pixels.push_back(s.session.pixel(sp, c));
  }
  return pixels;
}

TEST(WandCalibration, MeetsTheTargetsOnTheReferenceRigWithNoiseAndOutliers) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 1000;
  sim.noise_px = 0.3;
  sim.outlier_fraction = 0.05;
  sim.seed = 7;
  const SimulatedWandSession session = simulateWandSession(truth, sim);

  // No initial rig: the solve starts from a 60 degree lens (the truth is 66.6 degrees, a focal
  // length 13% off) without distortion (the truth has k1 = -0.06), principal point at the image
  // centre (where the truth's is).
  const WandCalibrationResult result = calibrateWand(session.session, WandCalibrationOptions{});
  EXPECT_LT(result.report.rms_px, 0.5);
  for (const CameraCalibrationReport& c : result.report.cameras) {
    EXPECT_LT(c.rms_px, 0.5) << c.name;
    EXPECT_GT(c.inliers, 50) << c.name;
  }
  const RigComparison cmp = compareRigs(result.rig, truth);
  EXPECT_LT(cmp.max_centre_m, 0.005);
  EXPECT_LT(cmp.max_rotation_deg, 0.1);
  EXPECT_LT(cmp.max_focal_rel, 0.003);
  // Focal length and lens together: the same rays land within a pixel wherever the camera
  // had samples (beyond them, in the image's corners, k1 and k2 are extrapolated).
  for (const Camera& c : result.rig.cameras()) {
    const Camera& t = truth.camera(*truth.findCamera(c.name()));
    EXPECT_LT(intrinsicsDifferencePx(c, t, seenPixels(session, c.name())), 1.0) << c.name();
  }
  // The floor marks put the rig in the world frame: no alignment needed to be near the truth.
  EXPECT_TRUE(result.report.metric);
  const RigComparison raw = compareRigs(result.rig, truth, false);
  EXPECT_LT(raw.max_centre_m, 0.01);
  EXPECT_LT(raw.max_rotation_deg, 0.1);
}

// The reference rig with each camera's principal point moved by up to `most_px` either way, as
// real lenses' sit.
Rig offCentreRig(double most_px, unsigned seed) {
  const Rig ring = referenceRig();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> off(-most_px, most_px);
  std::vector<Camera> cameras;
  for (const Camera& c : ring.cameras()) {
    Intrinsics k = c.intrinsics();
    k.cx += off(rng);
    k.cy += off(rng);
    cameras.emplace_back(c.name(), c.width(), c.height(), k, c.distortion(), c.rotation(),
                         c.translation());
  }
  return Rig(cameras, ring.nodes());
}

bool noteSays(const CalibrationReport& report, const std::string& text) {
  for (const std::string& note : report.notes)
    if (note.find(text) != std::string::npos) return true;
  return false;
}

// Principal points up to 12 px off centre: held at the centre they bend the whole rig (the
// rotations absorb them); the samples fit far better freed, so the solve frees them by itself,
// and says so.
TEST(WandCalibration, FreesThePrincipalPointsWhereTheSamplesShowThemOffCentre) {
  const Rig truth = offCentreRig(12, 5);
  WandSimulationOptions sim;
  sim.samples = 1000;
  sim.seed = 9;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  WandCalibrationOptions held;
  held.principal_point = WandCalibrationOptions::PrincipalPoint::kFixed;
  const RigComparison held_cmp = compareRigs(calibrateWand(s.session, held).rig, truth);
  const WandCalibrationResult result = calibrateWand(s.session, WandCalibrationOptions{});
  EXPECT_TRUE(noteSays(result.report, "principal points refined")) << result.report.notes.front();
  const RigComparison cmp = compareRigs(result.rig, truth);
  EXPECT_LT(cmp.max_rotation_deg, 0.5 * held_cmp.max_rotation_deg);
  EXPECT_LT(cmp.max_rotation_deg, 0.6);
  EXPECT_LT(result.report.rms_px, 0.45);
}

// Principal points where the solve starts (the image centre): freed, they would only fit the noise
// and trade against the rotations; they are held, and the report says why.
TEST(WandCalibration, HoldsThePrincipalPointsWhereFreeingThemFitsOnlyTheNoise) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 500;
  sim.seed = 9;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  const WandCalibrationResult result = calibrateWand(s.session, WandCalibrationOptions{});
  EXPECT_TRUE(noteSays(result.report, "principal points held")) << result.report.notes.front();
  for (const Camera& c : result.rig.cameras()) {
    EXPECT_EQ(c.intrinsics().cx, 511.5) << c.name();
    EXPECT_EQ(c.intrinsics().cy, 383.5) << c.name();
  }
  EXPECT_LT(compareRigs(result.rig, truth).max_rotation_deg, 0.05);
}

TEST(WandCalibration, RejectsTheOutliers) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 200;
  sim.outlier_fraction = 0.1;
  sim.seed = 3;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  const WandCalibrationResult result = calibrateWand(s.session, WandCalibrationOptions{});
  int outliers = 0, caught = 0, inliers = 0, kept = 0;
  for (int sp = 0; sp < s.session.sampleCount(); ++sp) {
    for (int c = 0; c < s.session.cameraCount(); ++c) {
      if (!s.session.has(sp, c)) continue;
      if (s.outlier[sp][c]) {
        ++outliers;
        caught += !result.inlier[sp][c];
      } else {
        ++inliers;
        kept += result.inlier[sp][c] && result.point_valid[sp];
      }
    }
  }
  ASSERT_GT(outliers, 50);
  EXPECT_GT(caught, 0.97 * outliers);
  EXPECT_GT(kept, 0.97 * inliers);
}

TEST(WandCalibration, ScaleFromTheWandLength) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 300;
  sim.wand_length_m = 0.5;
  sim.floor_marks_m.clear();
  sim.seed = 11;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  WandCalibrationOptions options;
  options.wand_length_m = 0.5;
  const WandCalibrationResult result = calibrateWand(s.session, options);
  EXPECT_TRUE(result.report.metric);
  const RigComparison cmp = compareRigs(result.rig, truth);
  EXPECT_NEAR(cmp.alignment.scale, 1.0, 0.003);
  EXPECT_LT(cmp.max_centre_m, 0.01);
}

TEST(WandCalibration, StartsFromAnInitialRigAndKeepsItsNodesAndStage) {
  Rig truth = referenceRig();
  truth.setStage(StageBox{{-1.8, -1.6, 0}, {1.7, 1.6, 2.5}});
  WandSimulationOptions sim;
  sim.samples = 150;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  WandCalibrationOptions options;
  options.initial_rig = truth;
  const WandCalibrationResult result = calibrateWand(s.session, options);
  EXPECT_EQ(result.rig.nodes(), truth.nodes());
  EXPECT_TRUE(result.rig.stage() == truth.stage());  // the floor marks keep the world
  EXPECT_LT(compareRigs(result.rig, truth).max_centre_m, 0.02);
}

// The initial rig has a spare camera the session lacks, and the session a camera the initial rig
// lacks: the nodes keep their hosts and cameras, the spare is left out, the new camera goes to a
// new node, and the report says both.
TEST(WandCalibration, KeepsTheInitialRigsNodesWhenTheCamerasDiffer) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 150;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  // The initial rig: the truth without cam12, plus a spare cam13, with hosts.
  std::vector<Camera> cameras;
  std::vector<int> index(truth.cameraCount(), -1);
  for (int c = 0; c < truth.cameraCount(); ++c) {
    if (truth.camera(c).name() == "cam12") continue;
    index[c] = int(cameras.size());
    cameras.push_back(truth.camera(c));
  }
  const Camera& model = truth.camera(0);
  cameras.emplace_back("cam13", model.width(), model.height(), model.intrinsics(),
                       model.distortion(), model.rotation(), model.translation());
  std::vector<RigNode> nodes;
  for (const RigNode& node : truth.nodes()) {
    RigNode n{node.name, "10.0.0." + node.name.substr(4), {}};
    for (int c : node.cameras)
      if (index[c] >= 0) n.cameras.push_back(index[c]);
    nodes.push_back(n);
  }
  nodes.back().cameras.push_back(int(cameras.size()) - 1);
  WandCalibrationOptions options;
  options.initial_rig = Rig(cameras, nodes);
  const WandCalibrationResult result = calibrateWand(s.session, options);
  ASSERT_EQ(result.rig.cameraCount(), 12);
  ASSERT_EQ(result.rig.nodeCount(), 5);
  for (int n = 0; n < 4; ++n) {
    EXPECT_EQ(result.rig.nodes()[n].name, truth.nodes()[n].name);
    EXPECT_EQ(result.rig.nodes()[n].host, "10.0.0." + std::to_string(n + 1));
  }
  const RigNode& added = result.rig.nodes()[4];
  EXPECT_EQ(added.name, "node5");
  ASSERT_EQ(added.cameras.size(), 1u);
  EXPECT_EQ(result.rig.camera(added.cameras[0]).name(), "cam12");
  std::string notes;
  for (const std::string& n : result.report.notes) notes += n + "\n";
  EXPECT_NE(notes.find("cameras not in the initial rig (cam12) are on new nodes (node5)"),
            std::string::npos)
      << notes;
  EXPECT_NE(notes.find("not in the session are left out: cam13"), std::string::npos) << notes;
  EXPECT_LT(compareRigs(result.rig, truth).max_centre_m, 0.02);
}

TEST(WandCalibration, NamesACameraThatSawNothing) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 100;
  SimulatedWandSession s = simulateWandSession(truth, sim);
  const int dark = *s.session.findCamera(truth.camera(5).name());
  for (int sp = 0; sp < s.session.sampleCount(); ++sp) s.session.clear(sp, dark);
  const std::string message =
      testing::errorOf([&] { calibrateWand(s.session, WandCalibrationOptions{}); });
  EXPECT_NE(message.find("camera " + truth.camera(5).name() + " saw nothing"), std::string::npos)
      << message;
}

TEST(WandCalibration, NamesACameraWithTooFewPoints) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 100;
  SimulatedWandSession s = simulateWandSession(truth, sim);
  const int cam = *s.session.findCamera(truth.camera(2).name());
  int kept = 0;
  for (int sp = 0; sp < s.session.sampleCount(); ++sp) {
    if (s.session.has(sp, cam) && ++kept > 5) s.session.clear(sp, cam);
  }
  const std::string message =
      testing::errorOf([&] { calibrateWand(s.session, WandCalibrationOptions{}); });
  EXPECT_NE(message.find("camera " + truth.camera(2).name() + " saw only 5 wand points"),
            std::string::npos)
      << message;
}

TEST(WandCalibration, SaysWhenTheSessionIsTooShort) {
  const Rig truth = referenceRig();
  WandSimulationOptions sim;
  sim.samples = 12;
  WandCalibrationOptions options;
  options.min_points_per_camera = 1;
  const SimulatedWandSession s = simulateWandSession(truth, sim);
  const std::string message = testing::errorOf([&] { calibrateWand(s.session, options); });
  EXPECT_NE(message.find("record a longer session"), std::string::npos) << message;
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

// End to end through images: every camera films the dark stage with the wand's LED (a 2 px wide
// spot, drawn where the camera's lens puts it) and a stray reflection now and then; the detector
// finds the point; the solve recovers the rig. Small images keep it fast.
TEST(WandCalibration, EndToEndThroughTheDetector) {
  RingRigSpec spec;
  spec.cameras = 8;
  spec.width = 320;
  spec.height = 240;
  const Rig truth = makeRingRig(spec);
  WandSimulationOptions sim;
  sim.samples = 400;
  sim.noise_px = 0;
  sim.outlier_fraction = 0;
  sim.dropout = 0;
  sim.seed = 9;
  const SimulatedWandSession path = simulateWandSession(truth, sim);  // the true points
  std::vector<WandCamera> cameras;
  for (const Camera& c : truth.cameras()) cameras.push_back({c.name(), c.width(), c.height()});
  WandSession session(cameras, static_cast<int>(path.points_m.size()));
  session.floor_marks = path.session.floor_marks;
  WandDetector detector;
  Image image;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  int ambiguous = 0;
  for (size_t s = 0; s < path.points_m.size(); ++s) {
    for (int c = 0; c < truth.cameraCount(); ++c) {
      const Camera& cam = truth.camera(c);
      std::vector<Eigen::Vector2d> spots;
      if (auto p = cam.project(path.points_m[s]); p && cam.inImage(*p)) spots.push_back(*p);
      if (u(rng) < 0.03) spots.emplace_back(u(rng) * cam.width(), u(rng) * cam.height());
      renderWandFrame(cam, spots, image);
      const WandDetection d = detector.detect(image.view());
      if (d.status == WandDetection::Status::kFound && cam.inImage(d.pixel))
        session.set(s, c, d.pixel);
      ambiguous += d.status == WandDetection::Status::kAmbiguous;
    }
  }
  EXPECT_GT(ambiguous, 0);  // the reflections next to the wand were rejected
  WandCalibrationOptions options;
  const WandCalibrationResult result = calibrateWand(session, options);
  EXPECT_LT(result.report.rms_px, 0.2);
  const RigComparison cmp = compareRigs(result.rig, truth);
  EXPECT_LT(cmp.max_centre_m, 0.01);
  EXPECT_LT(cmp.max_rotation_deg, 0.1);
}

}  // namespace
}  // namespace lumistage
