#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibration_report.h"
#include "core/capture/image.h"
#include "core/geometry/rig.h"

namespace lumistage {

// A checkerboard: cols x rows inner corners, squares square_m wide. Board frame: origin at the
// first inner corner, x along the rows of corners, y down the columns, z into the board (so a
// board lying face up on the floor has its z pointing down).
struct BoardSpec {
  int cols = 9;
  int rows = 6;
  double square_m = 0.08;
  Eigen::Vector3d corner(int i) const {
    return {square_m * (i % cols), square_m * (i / cols), 0.0};
  }
  int corners() const { return cols * rows; }
  // Throws Error unless the board can be read unambiguously: at least 3 inner corners a side,
  // cols + rows odd (an even board looks the same turned by 180 degrees, and half its views would
  // be read backwards), squares of a positive size.
  void check() const;
};

// The inner corners of the board in an image (OpenCV findChessboardCorners, refined by
// cornerSubPix), in the board's order; empty when the whole board is not found.
std::optional<std::vector<Eigen::Vector2d>> detectBoard(const ImageView& image,
                                                        const BoardSpec& board);

// One camera's view of the board at one instant (frame): all the inner corners.
struct BoardView {
  int frame = 0;
  int camera = 0;
  std::vector<Eigen::Vector2d> corners;
};

struct BoardSession {
  BoardSpec board;
  std::vector<std::string> camera_names;
  std::vector<Eigen::Vector2i> image_sizes;  // per camera
  std::vector<BoardView> views;
};

struct BoardCalibrationOptions {
  int min_views_per_camera = 3;
  int cameras_per_node = 3;
  // >= 0: the board of this frame lies on the floor and defines the world (origin at its first
  // corner, z up); otherwise the world is the first camera's frame.
  int floor_frame = -1;
};

struct BoardCalibrationResult {
  Rig rig;
  CalibrationReport report;
};

// Intrinsics per camera (OpenCV calibrateCamera: focal lengths, principal point, k1, k2), then
// extrinsics chained through boards seen by two cameras at once, then everything refined jointly
// (Ceres: intrinsics, camera poses and board poses). Throws Error naming the camera that has too
// few views or that no board links to the others.
BoardCalibrationResult calibrateBoards(const BoardSession& session,
                                       const BoardCalibrationOptions& options = {});

// The virtual studio's board session: a board image warped into every camera (with its lens
// distortion) at random poses over the stage, with a little blur and noise, through detectBoard.
// Returns the session and, per frame, the true board-to-world pose (x_world = R·x_board + t).
struct SimulatedBoardSession {
  BoardSession session;
  std::vector<Eigen::Matrix3d> board_R;
  std::vector<Eigen::Vector3d> board_t;
};
// Frame 0 lies flat on the floor at the origin (for floor_frame = 0); the rest are held up and
// turned towards random cameras.
SimulatedBoardSession simulateBoardSession(const Rig& rig, const BoardSpec& board, int frames,
                                           uint32_t seed);
// The image a camera sees of a board at a pose (mono8): for tests and the simulation. rays: the
// camera's undistorted normalised coordinates per pixel (cameraRays), computed when empty.
Image renderBoardView(const Camera& camera, const BoardSpec& board, const Eigen::Matrix3d& R,
                      const Eigen::Vector3d& t, const std::vector<Eigen::Vector2f>& rays = {});
std::vector<Eigen::Vector2f> cameraRays(const Camera& camera);  // NaN where undistortion fails

}  // namespace lumistage
