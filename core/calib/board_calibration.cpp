#include "core/calib/board_calibration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/base/error.h"
#include "core/calib/similarity.h"

namespace lumistage {

namespace {

cv::Mat grayOf(const ImageView& image) {
  const cv::Mat raw(image.height, image.width,
                    image.format == PixelFormat::kRgb8 ? CV_8UC3 : CV_8UC1,
                    const_cast<uint8_t*>(image.data));
  if (image.format == PixelFormat::kRgb8) {
    cv::Mat gray;
    cv::cvtColor(raw, gray, cv::COLOR_RGB2GRAY);
    return gray;
  }
  return raw;  // mono8; a Bayer frame's raw values are close enough to grey for a black and white
               // board
}

struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Pose inverse() const { return {R.transpose(), -R.transpose() * t}; }
  Pose operator*(const Pose& o) const { return {R * o.R, R * o.t + t}; }
};

Eigen::Vector3d angleAxisOf(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}
Eigen::Matrix3d rotationOf(const Eigen::Vector3d& aa) {
  const double angle = aa.norm();
  return angle < 1e-15 ? Eigen::Matrix3d::Identity()
                       : Eigen::AngleAxisd(angle, aa / angle).toRotationMatrix();
}

// A board corner seen by a camera: board pose (board to world), camera pose (world to camera),
// intrinsics fx fy cx cy k1 k2.
struct BoardCornerError {
  Eigen::Vector3d corner;
  Eigen::Vector2d observed;
  template <typename T>
  bool operator()(const T* board_r, const T* board_t, const T* cam_r, const T* cam_t, const T* k,
                  T* residual) const {
    const T c[3] = {T(corner.x()), T(corner.y()), T(corner.z())};
    T w[3], p[3];
    ceres::AngleAxisRotatePoint(board_r, c, w);
    for (int i = 0; i < 3; ++i) w[i] += board_t[i];
    ceres::AngleAxisRotatePoint(cam_r, w, p);
    for (int i = 0; i < 3; ++i) p[i] += cam_t[i];
    const T x = p[0] / p[2], y = p[1] / p[2], r2 = x * x + y * y;
    const T radial = T(1) + r2 * (k[4] + r2 * k[5]);
    residual[0] = k[0] * x * radial + k[2] - T(observed.x());
    residual[1] = k[1] * y * radial + k[3] - T(observed.y());
    return true;
  }
};

// Each camera calibrated on its own from its views of the board (views_of): its intrinsics
// (fx, fy, cx, cy, k1, k2) into k, the board's pose in each of its views into view_pose.
void calibrateEachCamera(const BoardSession& session, const std::vector<std::vector<int>>& views_of,
                         const BoardCalibrationOptions& options,
                         std::vector<std::array<double, 6>>& k, std::vector<Pose>& view_pose) {
  const int n = static_cast<int>(session.camera_names.size());
  std::vector<cv::Point3f> object;
  for (int i = 0; i < session.board.corners(); ++i) {
    const Eigen::Vector3d c = session.board.corner(i);
    object.emplace_back(float(c.x()), float(c.y()), float(c.z()));
  }
  for (int c = 0; c < n; ++c) {
    if (static_cast<int>(views_of[c].size()) < options.min_views_per_camera) {
      throw Error(
          fmt::format("camera {} saw the whole board in {} views; it needs at least {} "
                      "(show it the board at several angles)",
                      session.camera_names[c], views_of[c].size(), options.min_views_per_camera));
    }
    std::vector<std::vector<cv::Point3f>> objects;
    std::vector<std::vector<cv::Point2f>> images;
    for (int v : views_of[c]) {
      objects.push_back(object);
      std::vector<cv::Point2f> img;
      for (const Eigen::Vector2d& p : session.views[v].corners)
        img.emplace_back(float(p.x()), float(p.y()));
      images.push_back(img);
    }
    cv::Mat K, dist;
    std::vector<cv::Mat> rvecs, tvecs;
    const cv::Size size(session.image_sizes[c].x(), session.image_sizes[c].y());
    cv::calibrateCamera(objects, images, size, K, dist, rvecs, tvecs,
                        cv::CALIB_FIX_K3 | cv::CALIB_ZERO_TANGENT_DIST);
    k[c] = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2),
            K.at<double>(1, 2), dist.at<double>(0), dist.at<double>(1)};
    for (size_t i = 0; i < views_of[c].size(); ++i) {
      const Eigen::Vector3d r(rvecs[i].at<double>(0), rvecs[i].at<double>(1),
                              rvecs[i].at<double>(2));
      view_pose[views_of[c][i]] = {
          rotationOf(r), {tvecs[i].at<double>(0), tvecs[i].at<double>(1), tvecs[i].at<double>(2)}};
    }
  }
}

// Each camera's pose (world to camera, the world camera 0's frame), chained from camera 0 through
// frames where a camera already placed and one not yet placed both saw the board; a camera never
// linked so is refused.
std::vector<std::optional<Pose>> chainCameras(const BoardSession& session,
                                              const std::map<int, std::vector<int>>& views_in_frame,
                                              const std::vector<Pose>& view_pose) {
  const int n = static_cast<int>(session.camera_names.size());
  std::vector<std::optional<Pose>> camera_pose(n);  // world to camera
  camera_pose[0] = Pose{};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& [frame, views] : views_in_frame) {
      for (int a : views) {
        const int ca = session.views[a].camera;
        if (!camera_pose[ca]) continue;
        const Pose board_to_world = camera_pose[ca]->inverse() * view_pose[a];
        for (int b : views) {
          const int cb = session.views[b].camera;
          if (camera_pose[cb]) continue;
          camera_pose[cb] = view_pose[b] * board_to_world.inverse();
          grew = true;
        }
      }
    }
  }
  for (int c = 0; c < n; ++c) {
    if (!camera_pose[c]) {
      throw Error(
          fmt::format("camera {} never saw the board at the same time as a camera linked "
                      "to {}: show the board to it and a neighbour together",
                      session.camera_names[c], session.camera_names[0]));
    }
  }
  return camera_pose;
}

}  // namespace

void BoardSpec::check() const {
  if (cols < 3 || rows < 3)
    throw Error(fmt::format("board: {}x{} inner corners: at least 3 a side wanted", cols, rows));
  if ((cols + rows) % 2 == 0)
    throw Error(fmt::format(
        "board: {}x{} inner corners: cols + rows must be odd (such a board looks the same turned "
        "by 180 degrees, so its views cannot be told apart); count the inner corners, not the "
        "squares, or use a board with one square more or less on a side",
        cols, rows));
  if (!(square_m > 0 && std::isfinite(square_m)))
    throw Error(fmt::format("board: square size {} m: a positive length wanted", square_m));
}

std::optional<std::vector<Eigen::Vector2d>> detectBoard(const ImageView& image,
                                                        const BoardSpec& board) {
  board.check();
  const cv::Mat gray = grayOf(image);
  // The sector-based detector (Duda & Frese 2018): more robust to blur, small and oblique boards
  // than the classic one, bounded in time when there is no board, and sub-pixel by itself.
  std::vector<cv::Point2f> corners;
  const cv::Size pattern(board.cols, board.rows);
  if (!cv::findChessboardCornersSB(gray, pattern, corners, cv::CALIB_CB_NORMALIZE_IMAGE))
    return std::nullopt;
  std::vector<Eigen::Vector2d> out;
  for (const cv::Point2f& p : corners) out.emplace_back(p.x, p.y);
  // OpenCV may list the corners from either end (the board turned by 180 degrees). The board's
  // convention: the outer square diagonally beyond the first corner is black; beyond the last
  // corner it is then white (cols + rows odd) or black (even: such a board is ambiguous).
  auto beyond = [&](int corner, int inner) {
    const Eigen::Vector2d p = out[corner] + 0.5 * (out[corner] - out[inner]);
    const int x = std::clamp(static_cast<int>(std::lround(p.x())), 0, gray.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(p.y())), 0, gray.rows - 1);
    return int(gray.at<uint8_t>(y, x));
  };
  const int last = board.corners() - 1;
  if (beyond(0, board.cols + 1) > beyond(last, last - board.cols - 1))
    std::reverse(out.begin(), out.end());
  return out;
}

BoardCalibrationResult calibrateBoards(const BoardSession& session,
                                       const BoardCalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int n = static_cast<int>(session.camera_names.size());
  const BoardSpec& board = session.board;
  board.check();
  std::vector<std::vector<int>> views_of(n);
  for (size_t v = 0; v < session.views.size(); ++v) {
    const BoardView& view = session.views[v];
    if (view.camera < 0 || view.camera >= n ||
        static_cast<int>(view.corners.size()) != board.corners())
      throw Error(fmt::format("board view {} is malformed (camera {}, {} corners)", v, view.camera,
                              view.corners.size()));
    views_of[view.camera].push_back(static_cast<int>(v));
  }
  // 1. Intrinsics of each camera on its own, and the board's pose in each view.
  std::vector<std::array<double, 6>> k(n);
  std::vector<Pose> view_pose(session.views.size());  // board to camera
  calibrateEachCamera(session, views_of, options, k, view_pose);
  // 2. Extrinsics: chained from camera 0 through frames where a known and an unknown camera both
  // saw the board.
  std::map<int, std::vector<int>> views_in_frame;
  for (size_t v = 0; v < session.views.size(); ++v)
    views_in_frame[session.views[v].frame].push_back(int(v));
  const std::vector<std::optional<Pose>> camera_pose =
      chainCameras(session, views_in_frame, view_pose);
  // 3. Joint refinement.
  std::map<int, std::pair<Eigen::Vector3d, Eigen::Vector3d>> board_params;  // frame -> r, t
  for (const auto& [frame, views] : views_in_frame) {
    const int v = views.front();
    const Pose p = camera_pose[session.views[v].camera]->inverse() * view_pose[v];
    board_params[frame] = {angleAxisOf(p.R), p.t};
  }
  std::vector<Eigen::Vector3d> cam_r(n), cam_t(n);
  for (int c = 0; c < n; ++c)
    cam_r[c] = angleAxisOf(camera_pose[c]->R), cam_t[c] = camera_pose[c]->t;
  ceres::Problem problem;
  for (const BoardView& view : session.views) {
    auto& [br, bt] = board_params[view.frame];
    for (int i = 0; i < board.corners(); ++i) {
      auto* cost = new ceres::AutoDiffCostFunction<BoardCornerError, 2, 3, 3, 3, 3, 6>(
          new BoardCornerError{board.corner(i), view.corners[i]});
      problem.AddResidualBlock(cost, new ceres::HuberLoss(1.0), br.data(), bt.data(),
                               cam_r[view.camera].data(), cam_t[view.camera].data(),
                               k[view.camera].data());
    }
  }
  problem.SetParameterBlockConstant(cam_r[0].data());
  problem.SetParameterBlockConstant(cam_t[0].data());
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = 100;
  solver.num_threads = 2;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);

  std::vector<Camera> cameras;
  for (int c = 0; c < n; ++c) {
    cameras.emplace_back(session.camera_names[c], session.image_sizes[c].x(),
                         session.image_sizes[c].y(),
                         Intrinsics{k[c][0], k[c][1], k[c][2], k[c][3], 0},
                         Distortion{k[c][4], k[c][5], 0, 0, 0}, rotationOf(cam_r[c]), cam_t[c]);
  }
  BoardCalibrationResult result;
  result.rig = Rig(cameras, dealCamerasToNodes(n, options.cameras_per_node));
  CalibrationReport& r = result.report;
  r.method = "board";
  r.samples = static_cast<int>(views_in_frame.size());
  r.metric = true;
  // The world: the floor board's frame turned face up (x along its rows, y, z up), else camera 0's.
  Similarity world;
  if (options.floor_frame >= 0) {
    const auto it = board_params.find(options.floor_frame);
    if (it == board_params.end())
      throw Error(
          fmt::format("floor frame {}: no camera saw the whole board in it", options.floor_frame));
    const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
    const Pose board_to_world{rotationOf(it->second.first), it->second.second};
    world.R = flip * board_to_world.R.transpose();
    world.t = -world.R * board_to_world.t;
    r.notes.push_back(fmt::format("the board of frame {} is the floor", options.floor_frame));
  } else {
    r.notes.push_back(
        fmt::format("no floor frame: the world is camera {}'s frame", session.camera_names[0]));
  }
  result.rig = world.apply(result.rig);
  for (int c = 0; c < n; ++c) {
    const Camera& cam = result.rig.camera(c);
    std::vector<Eigen::Vector2d> observed, residuals;
    for (int v : views_of[c]) {
      const BoardView& view = session.views[v];
      const auto& [br, bt] = board_params[view.frame];
      const Eigen::Matrix3d R = rotationOf(br);
      for (int i = 0; i < board.corners(); ++i) {
        const std::optional<Eigen::Vector2d> p =
            cam.project(world.apply(Eigen::Vector3d(R * board.corner(i) + bt)));
        if (!p) continue;
        observed.push_back(view.corners[i]);
        residuals.push_back(*p - view.corners[i]);
      }
    }
    r.cameras.push_back(
        makeCameraReport(cam, observed, residuals, static_cast<int>(observed.size())));
  }
  finishReport(r);
  r.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// ---- Simulation
// ----------------------------------------------------------------------------------

std::vector<Eigen::Vector2f> cameraRays(const Camera& camera) {
  std::vector<Eigen::Vector2f> rays(static_cast<size_t>(camera.width()) * camera.height());
  for (int y = 0; y < camera.height(); ++y) {
    for (int x = 0; x < camera.width(); ++x) {
      const std::optional<Eigen::Vector2d> u = camera.undistortPixel(Eigen::Vector2d(x, y));
      rays[static_cast<size_t>(y) * camera.width() + x] =
          u ? Eigen::Vector2f(camera.pixelToNormalized(*u).cast<float>())
            : Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
    }
  }
  return rays;
}

Image renderBoardView(const Camera& camera, const BoardSpec& board, const Eigen::Matrix3d& R,
                      const Eigen::Vector3d& t, const std::vector<Eigen::Vector2f>& given_rays) {
  const std::vector<Eigen::Vector2f> own_rays =
      given_rays.empty() ? cameraRays(camera) : std::vector<Eigen::Vector2f>{};
  const std::vector<Eigen::Vector2f>& rays = given_rays.empty() ? own_rays : given_rays;
  // The board's texture: squares of S pixels and a white margin of one square.
  constexpr int S = 24;
  const int tex_w = (board.cols + 3) * S, tex_h = (board.rows + 3) * S;
  cv::Mat texture(tex_h, tex_w, CV_8UC1, cv::Scalar(235));
  for (int sy = 0; sy <= board.rows; ++sy) {
    for (int sx = 0; sx <= board.cols; ++sx) {
      if ((sx + sy) % 2 == 0) texture(cv::Rect(S + sx * S, S + sy * S, S, S)).setTo(20);
    }
  }
  // Board point (x, y) -> texture: inner corner i sits between squares i and i+1.
  const double px_per_m = S / board.square_m;
  const double u0 = 2 * S - 0.5, v0 = 2 * S - 0.5;
  const Eigen::Matrix3d R_cb = camera.rotation() * R;
  const Eigen::Vector3d t_cb = camera.rotation() * t + camera.translation();
  const Eigen::Vector3d normal = R_cb.col(2);
  const double plane = normal.dot(t_cb);
  cv::Mat map_x(camera.height(), camera.width(), CV_32FC1),
      map_y(camera.height(), camera.width(), CV_32FC1);
  for (int y = 0; y < camera.height(); ++y) {
    for (int x = 0; x < camera.width(); ++x) {
      float mx = -10, my = -10;
      const Eigen::Vector2f& n = rays[static_cast<size_t>(y) * camera.width() + x];
      if (std::isfinite(n.x())) {
        const Eigen::Vector3d d(n.x(), n.y(), 1.0);
        const double denom = normal.dot(d);
        if (std::abs(denom) > 1e-9 && plane / denom > 0) {
          const Eigen::Vector3d b = R_cb.transpose() * (plane / denom * d - t_cb);
          mx = static_cast<float>(u0 + b.x() * px_per_m);
          my = static_cast<float>(v0 + b.y() * px_per_m);
        }
      }
      map_x.at<float>(y, x) = mx, map_y.at<float>(y, x) = my;
    }
  }
  cv::Mat view;
  cv::remap(texture, view, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(70));
  cv::GaussianBlur(view, view, cv::Size(0, 0), 0.6);
  cv::Mat noise(view.size(), CV_16SC1);
  cv::randn(noise, 0, 2);
  cv::Mat noisy;
  view.convertTo(noisy, CV_16SC1);
  noisy += noise;
  noisy.convertTo(view, CV_8UC1);
  Image out;
  out.resize(PixelFormat::kMono8, camera.width(), camera.height());
  for (int y = 0; y < camera.height(); ++y)
    std::copy_n(view.ptr<uint8_t>(y), camera.width(),
                out.pixels.data() + size_t(y) * camera.width());
  return out;
}

SimulatedBoardSession simulateBoardSession(const Rig& rig, const BoardSpec& board, int frames,
                                           uint32_t seed) {
  board.check();
  SimulatedBoardSession sim;
  sim.session.board = board;
  for (const Camera& c : rig.cameras()) {
    sim.session.camera_names.push_back(c.name());
    sim.session.image_sizes.emplace_back(c.width(), c.height());
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<Eigen::Vector2f>> rays;
  for (const Camera& c : rig.cameras()) rays.push_back(cameraRays(c));
  const Eigen::Vector3d half(0.5 * board.square_m * (board.cols - 1),
                             0.5 * board.square_m * (board.rows - 1), 0);
  for (int f = 0; f < frames; ++f) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    if (f == 0) {
      R = Eigen::Vector3d(1, -1, -1).asDiagonal();  // face up, first corner at the origin
      t.setZero();
    } else {
      // Odd frames: held up in front of the cameras in turn, 1.4 to 2.4 m from the one it faces,
      // somewhere in its view (so that its samples cover the image). Even frames: over the stage
      // centre, facing between two neighbouring cameras, which links them. Tilted and turned a
      // little.
      const int k = (f - 1) / 2;
      const Camera& target = rig.camera(k % rig.cameraCount());
      const Camera& neighbour = rig.camera((k + 1) % rig.cameraCount());
      Eigen::Vector3d centre, towards;
      if (f % 2 == 1) {
        const Eigen::Vector2d aim(target.width() * (0.5 + 0.3 * u(rng)),
                                  target.height() * (0.5 + 0.3 * u(rng)));
        centre = target.centre() + (1.9 + 0.5 * u(rng)) * target.unproject(aim)->direction;
        towards = target.centre();
      } else {
        centre = Eigen::Vector3d(0.4 * u(rng), 0.4 * u(rng), 1.2 + 0.3 * u(rng));
        towards = 0.5 * (target.centre() + neighbour.centre());
      }
      Eigen::Vector3d z = (centre - towards).normalized();  // into the board, away from it
      z = (Eigen::AngleAxisd(0.5 * u(rng), Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(0.4 * u(rng), Eigen::Vector3d::UnitX()) * z)
              .normalized();
      Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
      x = Eigen::AngleAxisd(0.4 * u(rng), z) * x;
      R.col(0) = x;
      R.col(1) = z.cross(x);
      R.col(2) = z;
      t = centre - R * half;
    }
    sim.board_R.push_back(R);
    sim.board_t.push_back(t);
    for (int c = 0; c < rig.cameraCount(); ++c) {
      const Camera& cam = rig.camera(c);
      // Only the front of the board has the pattern.
      const Eigen::Vector3d to_camera = (cam.centre() - (R * half + t)).normalized();
      if (-R.col(2).dot(to_camera) < 0.5) continue;  // within 60 degrees of face-on
      bool inside = true;
      for (int i : {0, board.cols - 1, board.corners() - board.cols, board.corners() - 1}) {
        const std::optional<Eigen::Vector2d> p = cam.project(R * board.corner(i) + t);
        inside = inside && p && p->x() > 20 && p->y() > 20 && p->x() < cam.width() - 21 &&
                 p->y() < cam.height() - 21;
      }
      if (!inside) continue;
      const Image image = renderBoardView(cam, board, R, t, rays[c]);
      std::optional<std::vector<Eigen::Vector2d>> corners = detectBoard(image.view(), board);
      if (corners) sim.session.views.push_back({f, c, std::move(*corners)});
    }
  }
  return sim;
}

}  // namespace lumistage
