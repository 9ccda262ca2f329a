#include "core/calib/board_calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>

#include "core/calib/similarity.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

Rig smallRig() {
  RingRigSpec spec;
  spec.cameras = 6;
  spec.width = 640;
  spec.height = 480;
  spec.radius_m = 3.0;
  return makeRingRig(spec);
}

BoardSpec studioBoard() {
  return BoardSpec{9, 6, 0.1};
}

TEST(BoardCalibration, DetectsTheCornersInTheBoardsOrder) {
  const Rig rig = smallRig();
  const Camera& cam = rig.camera(0);
  const BoardSpec board = studioBoard();
  // Facing the camera, upright, then the same turned upside down: the first corner stays put.
  for (double roll : {0.0, M_PI}) {
    Eigen::Matrix3d R;
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 1.2) - cam.centre()).normalized();
    Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
    x = Eigen::AngleAxisd(roll, z) * x;
    R << x, z.cross(x), z;
    const Eigen::Vector3d t = Eigen::Vector3d(0, 0, 1.2) - R * Eigen::Vector3d(0.4, 0.25, 0);
    const Image image = renderBoardView(cam, board, R, t);
    const auto corners = detectBoard(image.view(), board);
    ASSERT_TRUE(corners) << "roll " << roll;
    double worst = 0;
    for (int i = 0; i < board.corners(); ++i) {
      worst = std::max(worst, ((*corners)[i] - *cam.project(R * board.corner(i) + t)).norm());
    }
    EXPECT_LT(worst, 0.3) << "roll " << roll;
  }
}

TEST(BoardCalibration, RecoversTheRigFromRenderedBoardViews) {
  const Rig truth = smallRig();
  // 25 frames: the floor, then in turn close to a camera and between two (about 40 views).
  const SimulatedBoardSession sim = simulateBoardSession(truth, studioBoard(), 25, 4);
  BoardCalibrationOptions options;
  options.floor_frame = 0;
  const BoardCalibrationResult result = calibrateBoards(sim.session, options);
  EXPECT_LT(result.report.rms_px, 0.3);
  EXPECT_TRUE(result.report.metric);
  // The floor board puts the rig in the world frame, to scale: compared without alignment.
  const RigComparison cmp = compareRigs(result.rig, truth, false);
  EXPECT_LT(cmp.max_centre_m, 0.03);
  EXPECT_LT(cmp.max_rotation_deg, 0.5);
  EXPECT_LT(cmp.max_focal_rel, 0.01);
}

// A board session without images: the corners projected through the true cameras.
BoardSession projectedSession(const Rig& rig, const BoardSpec& board, int frames) {
  BoardSession session;
  session.board = board;
  for (const Camera& c : rig.cameras()) {
    session.camera_names.push_back(c.name());
    session.image_sizes.emplace_back(c.width(), c.height());
  }
  for (int f = 0; f < frames; ++f) {
    const Camera& target = rig.camera(f % rig.cameraCount());
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 1.2) - target.centre()).normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
    Eigen::Matrix3d R;
    R << x, z.cross(x), z;
    R = Eigen::AngleAxisd(0.3 * (f % 3 - 1), Eigen::Vector3d::UnitZ()) * R;
    const Eigen::Vector3d t = Eigen::Vector3d(0, 0, 1.2) - R * Eigen::Vector3d(0.4, 0.25, 0);
    for (int c = 0; c < rig.cameraCount(); ++c) {
      BoardView view{f, c, {}};
      for (int i = 0; i < board.corners(); ++i) {
        const auto p = rig.camera(c).project(R * board.corner(i) + t);
        if (p && rig.camera(c).inImage(*p) && (rig.camera(c).centre() - t).dot(R.col(2)) < 0)
          view.corners.push_back(*p);
      }
      if (static_cast<int>(view.corners.size()) == board.corners()) session.views.push_back(view);
    }
  }
  return session;
}

// A board of 8x6 inner corners (9x7 squares, a common one) looks the same turned by 180 degrees:
// half its views would be read backwards and the rig would come out wrong (12 px RMS, cameras
// metres off). It is refused before any image is read.
TEST(BoardCalibration, RefusesABoardThatReadsTheSameTurnedAround) {
  const std::string message = testing::errorOf([] { BoardSpec{8, 6, 0.1}.check(); });
  EXPECT_NE(message.find("board: 8x6 inner corners: cols + rows must be odd"), std::string::npos)
      << message;
  EXPECT_NE(testing::errorOf([] {
              BoardSpec{9, 2, 0.1}.check();
            }).find("at least 3"),
            std::string::npos);
  EXPECT_NE(testing::errorOf([] {
              BoardSpec{9, 6, 0}.check();
            }).find("square size 0 m"),
            std::string::npos);
  EXPECT_NO_THROW(BoardSpec({9, 6, 0.1}).check());
  BoardSession session = projectedSession(smallRig(), studioBoard(), 12);
  session.board.cols = 8;
  EXPECT_NE(testing::errorOf([&] { calibrateBoards(session); }).find("cols + rows must be odd"),
            std::string::npos);
}

TEST(BoardCalibration, NamesACameraWithTooFewViews) {
  const Rig truth = smallRig();
  BoardSession session = projectedSession(truth, studioBoard(), 12);
  std::erase_if(session.views, [](const BoardView& v) { return v.camera == 0 && v.frame > 0; });
  const std::string message = testing::errorOf([&] { calibrateBoards(session); });
  EXPECT_NE(message.find("camera " + truth.camera(0).name() + " saw the whole board in 1 views"),
            std::string::npos)
      << message;
}

TEST(BoardCalibration, NamesACameraThatNoBoardLinks) {
  const Rig truth = smallRig();
  BoardSession session = projectedSession(truth, studioBoard(), 12);
  // Camera 4 keeps only the views that no other camera shares.
  std::erase_if(session.views, [&](const BoardView& v) {
    if (v.camera != 4) return false;
    return std::count_if(session.views.begin(), session.views.end(),
                         [&](const BoardView& o) { return o.frame == v.frame; }) > 1;
  });
  for (int f = 100; f < 103; ++f) {
    BoardView alone = session.views.front();
    alone.camera = 4;
    alone.frame = f;
    session.views.push_back(alone);
  }
  const std::string message = testing::errorOf([&] { calibrateBoards(session); });
  EXPECT_NE(
      message.find("camera " + truth.camera(4).name() + " never saw the board at the same time"),
      std::string::npos)
      << message;
}

}  // namespace
}  // namespace lumistage
