#include "core/calib/wand_calibration.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include "core/base/error.h"
#include "core/calib/bundle_adjuster.h"
#include "core/calib/similarity.h"

namespace lumistage {

namespace {

// The undistorted normalised image coordinates of a pixel of a bundle camera (fixed point
// iteration of the radial model; converges for any lens that is monotonic over its image).
Eigen::Vector2d normalizedOf(const BundleCamera& c, const Eigen::Vector2d& pixel) {
  const Eigen::Vector2d xd((pixel.x() - c.cx) / c.focal_px, (pixel.y() - c.cy) / c.focal_px);
  Eigen::Vector2d x = xd;
  for (int i = 0; i < 20; ++i) {
    const double r2 = x.squaredNorm();
    x = xd / (1 + r2 * (c.k1 + r2 * c.k2));
  }
  return x;
}

Eigen::Matrix3d rotationOf(const BundleCamera& c) {
  const double angle = c.rotation.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, c.rotation / angle).toRotationMatrix();
}

Eigen::Vector3d angleAxisOf(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

class WandSolver {
 public:
  WandSolver(const WandSession& session, const WandCalibrationOptions& options)
      : s_(session),
        o_(options),
        n_(session.cameraCount()),
        m_(session.sampleCount()),
        refine_principal_point_(options.principal_point ==
                                WandCalibrationOptions::PrincipalPoint::kRefined) {}

  WandCalibrationResult solve();

 private:
  const std::string& name(int c) const { return s_.cameras()[c].name; }
  void report(const std::string& stage, int done, int total) const {
    if (o_.progress) o_.progress(stage, done, total);
  }
  void checkSession() const;
  void initialIntrinsics();
  void initialPair();
  void resect(int camera);
  // Triangulates a sample from the registered cameras that saw it, dropping the worst view while
  // any is off by more than threshold_px; marks the views kept in agree_.
  void triangulate(int sample, double threshold_px);
  void triangulateAll(double threshold_px) {
    for (int sp = 0; sp < m_; ++sp) triangulate(sp, threshold_px);
  }
  std::vector<BundleObservation> observations() const;
  BundleResult bundle(bool refine_intrinsics, bool refine_distortion, double huber_px,
                      int iterations);
  // Re-decides which observations agree with the solution; returns the threshold used.
  double rejectOutliers();
  void alignGauge(WandCalibrationResult& result) const;
  Rig makeRig(std::vector<std::string>& notes) const;

  const WandSession& s_;
  const WandCalibrationOptions& o_;
  const int n_, m_;
  std::vector<BundleCamera> cams_;
  std::vector<uint8_t> registered_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<uint8_t> valid_;
  std::vector<std::vector<uint8_t>> agree_;  // [sample][camera]
  int fixed_ = 0, scale_ = 1;
  std::vector<std::string> notes_;
  // Whether the bundle adjustments free the principal points: from the start for kRefined; for
  // kAuto, decidePrincipalPoints() tries them freed at the end.
  bool refine_principal_point_;
  // kAuto: after the solve with the principal points held, the same solve's last round with them
  // freed, kept if it fits the observations better by WandCalibrationOptions::kPrincipalPointGain.
  void decidePrincipalPoints();
};

void WandSolver::checkSession() const {
  if (n_ < 2)
    throw Error(
        fmt::format("a wand calibration needs two or more cameras, the session has {}", n_));
  for (int c = 0; c < n_; ++c) {
    const int seen = s_.observationCount(c);
    if (seen == 0) {
      throw Error(fmt::format(
          "camera {} saw nothing: no wand point in any of its images (is it connected, exposed "
          "for the wand, and does the wand pass through its view?)",
          name(c)));
    }
    if (seen < o_.min_points_per_camera) {
      throw Error(
          fmt::format("camera {} saw only {} wand points; a camera needs at least {} (wave "
                      "the wand through its view)",
                      name(c), seen, o_.min_points_per_camera));
    }
  }
  int shared = 0;
  for (int sp = 0; sp < m_; ++sp) shared += s_.viewCount(sp) >= 2;
  if (shared < o_.min_samples) {
    throw Error(
        fmt::format("only {} wand samples were seen by two or more cameras; at least {} are "
                    "needed (record a longer session)",
                    shared, o_.min_samples));
  }
}

void WandSolver::initialIntrinsics() {
  cams_.assign(n_, BundleCamera{});
  for (int c = 0; c < n_; ++c) {
    const WandCamera& wc = s_.cameras()[c];
    BundleCamera& k = cams_[c];
    std::optional<int> known;
    if (o_.initial_rig) known = o_.initial_rig->findCamera(wc.name);
    if (known) {
      const Camera& ic = o_.initial_rig->camera(*known);
      const double sx = double(wc.width) / ic.width(), sy = double(wc.height) / ic.height();
      k.focal_px = 0.5 * (ic.intrinsics().fx * sx + ic.intrinsics().fy * sy);
      k.cx = (ic.intrinsics().cx + 0.5) * sx - 0.5;
      k.cy = (ic.intrinsics().cy + 0.5) * sy - 0.5;
      k.k1 = ic.distortion().k1, k.k2 = ic.distortion().k2;
    } else {
      k.focal_px = 0.5 * wc.width / std::tan(0.5 * o_.nominal_hfov_deg * M_PI / 180);
      k.cx = 0.5 * (wc.width - 1), k.cy = 0.5 * (wc.height - 1);
    }
  }
  if (o_.initial_rig) {
    for (int c = 0; c < n_; ++c) {
      if (!o_.initial_rig->findCamera(name(c)))
        notes_.push_back(
            fmt::format("camera {} is not in the initial rig: it starts from a {} "
                        "degree field of view",
                        name(c), o_.nominal_hfov_deg));
    }
  }
}

void WandSolver::initialPair() {
  int best_a = -1, best_b = -1, best = -1;
  for (int a = 0; a < n_; ++a) {
    for (int b = a + 1; b < n_; ++b) {
      int common = 0;
      for (int sp = 0; sp < m_; ++sp) common += s_.has(sp, a) && s_.has(sp, b);
      if (common > best) best = common, best_a = a, best_b = b;
    }
  }
  if (best < 8) {
    throw Error(
        fmt::format("no two cameras share 8 wand samples (the best, {} and {}, share {}): "
                    "the cameras' views must overlap",
                    name(best_a), name(best_b), best));
  }
  std::vector<cv::Point2d> pa, pb;
  std::vector<int> samples;
  for (int sp = 0; sp < m_; ++sp) {
    if (!s_.has(sp, best_a) || !s_.has(sp, best_b)) continue;
    const Eigen::Vector2d xa = normalizedOf(cams_[best_a], s_.pixel(sp, best_a));
    const Eigen::Vector2d xb = normalizedOf(cams_[best_b], s_.pixel(sp, best_b));
    pa.emplace_back(xa.x(), xa.y());
    pb.emplace_back(xb.x(), xb.y());
    samples.push_back(sp);
  }
  const double f = 0.5 * (cams_[best_a].focal_px + cams_[best_b].focal_px);
  cv::Mat mask;
  const cv::Mat I = cv::Mat::eye(3, 3, CV_64F);
  const cv::Mat E =
      cv::findEssentialMat(pa, pb, I, cv::RANSAC, 0.9999, o_.ransac_threshold_px / f, mask);
  if (E.rows != 3 || E.cols != 3) {
    throw Error(
        fmt::format("cameras {} and {} (the pair sharing most samples): no consistent "
                    "two-view geometry found",
                    name(best_a), name(best_b)));
  }
  cv::Mat R, t;
  const int inliers = cv::recoverPose(E, pa, pb, I, R, t, mask);
  if (inliers < 8) {
    throw Error(
        fmt::format("cameras {} and {}: only {} of their {} shared samples fit one "
                    "two-view geometry",
                    name(best_a), name(best_b), inliers, best));
  }
  Eigen::Matrix3d Re;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
  }
  cams_[best_a].rotation.setZero();
  cams_[best_a].translation.setZero();
  cams_[best_b].rotation = angleAxisOf(Re);
  cams_[best_b].translation = {t.at<double>(0), t.at<double>(1), t.at<double>(2)};
  registered_.assign(n_, 0);
  registered_[best_a] = registered_[best_b] = 1;
  fixed_ = best_a, scale_ = best_b;
}

void WandSolver::triangulate(int sp, double threshold_px) {
  std::vector<int> views;
  for (int c = 0; c < n_; ++c) {
    agree_[sp][c] = 0;
    if (registered_[c] && s_.has(sp, c)) views.push_back(c);
  }
  valid_[sp] = 0;
  while (views.size() >= 2) {
    Eigen::MatrixXd A(2 * views.size(), 4);
    for (size_t i = 0; i < views.size(); ++i) {
      const BundleCamera& c = cams_[views[i]];
      Eigen::Matrix<double, 3, 4> P;
      P.leftCols<3>() = rotationOf(c);
      P.col(3) = c.translation;
      const Eigen::Vector2d x = normalizedOf(c, s_.pixel(sp, views[i]));
      A.row(2 * i) = x.x() * P.row(2) - P.row(0);
      A.row(2 * i + 1) = x.y() * P.row(2) - P.row(1);
    }
    const Eigen::Vector4d X =
        Eigen::JacobiSVD<Eigen::MatrixXd>(A, Eigen::ComputeFullV).matrixV().col(3);
    if (std::abs(X[3]) < 1e-12) return;
    const Eigen::Vector3d point = X.head<3>() / X[3];
    double worst = -1;
    size_t worst_i = 0;
    for (size_t i = 0; i < views.size(); ++i) {
      Eigen::Vector2d pixel;
      const double e = projectBundle(cams_[views[i]], point, pixel)
                           ? (pixel - s_.pixel(sp, views[i])).norm()
                           : std::numeric_limits<double>::infinity();
      if (e > worst) worst = e, worst_i = i;
    }
    if (worst <= threshold_px) {
      points_[sp] = point;
      valid_[sp] = 1;
      for (int c : views) agree_[sp][c] = 1;
      return;
    }
    views.erase(views.begin() + static_cast<long>(worst_i));
  }
}

void WandSolver::resect(int camera) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (int sp = 0; sp < m_; ++sp) {
    if (!valid_[sp] || !s_.has(sp, camera)) continue;
    const Eigen::Vector2d x = normalizedOf(cams_[camera], s_.pixel(sp, camera));
    object.emplace_back(points_[sp].x(), points_[sp].y(), points_[sp].z());
    image.emplace_back(x.x(), x.y());
  }
  if (object.size() < 12) {
    throw Error(
        fmt::format("camera {} shares only {} wand samples with the cameras solved before "
                    "it; it needs 12 (its view must overlap theirs)",
                    name(camera), object.size()));
  }
  const cv::Mat I = cv::Mat::eye(3, 3, CV_64F);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const bool ok =
      cv::solvePnPRansac(object, image, I, cv::noArray(), rvec, tvec, false, 500,
                         static_cast<float>(o_.ransac_threshold_px / cams_[camera].focal_px), 0.999,
                         inliers, cv::SOLVEPNP_EPNP);
  if (!ok || inliers.size() < 8) {
    throw Error(fmt::format("camera {}: no pose fits its view of the wand ({} of {} samples agree)",
                            name(camera), inliers.size(), object.size()));
  }
  std::vector<cv::Point3d> object_in;
  std::vector<cv::Point2d> image_in;
  for (int i : inliers) object_in.push_back(object[i]), image_in.push_back(image[i]);
  cv::solvePnP(object_in, image_in, I, cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
  cams_[camera].rotation = {rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)};
  cams_[camera].translation = {tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)};
  registered_[camera] = 1;
}

std::vector<BundleObservation> WandSolver::observations() const {
  std::vector<BundleObservation> obs;
  for (int sp = 0; sp < m_; ++sp) {
    if (!valid_[sp]) continue;
    for (int c = 0; c < n_; ++c) {
      if (agree_[sp][c]) obs.push_back({c, sp, s_.pixel(sp, c)});
    }
  }
  return obs;
}

BundleResult WandSolver::bundle(bool refine_intrinsics, bool refine_distortion, double huber_px,
                                int iterations) {
  BundleOptions options;
  options.refine_intrinsics = refine_intrinsics;
  options.refine_distortion = refine_distortion;
  options.refine_principal_point = refine_principal_point_;
  options.huber_px = huber_px;
  options.max_iterations = iterations;
  options.fixed_camera = fixed_;
  options.scale_camera = scale_;
  return adjustBundle(cams_, points_, observations(), options);
}

void WandSolver::decidePrincipalPoints() {
  const std::vector<BundleCamera> held_cams = cams_;
  const std::vector<Eigen::Vector3d> held_points = points_;
  refine_principal_point_ = true;
  const BundleResult freed = bundle(true, o_.refine_distortion, 0, 100);
  const double gain = 1 - freed.final_rms_px / freed.initial_rms_px;
  const bool keep = gain >= WandCalibrationOptions::kPrincipalPointGain;
  if (keep) {
    // Freed, the outliers judged again against the better cameras.
    rejectOutliers();
    bundle(true, o_.refine_distortion, 0, 100);
    double most = 0;
    for (size_t c = 0; c < cams_.size(); ++c)
      most =
          std::max(most, std::hypot(cams_[c].cx - held_cams[c].cx, cams_[c].cy - held_cams[c].cy));
    notes_.push_back(fmt::format(
        "principal points refined: freed, they fit the samples {:.1f}% better ({:.3f} -> {:.3f} px "
        "RMS) and moved up to {:.1f} px",
        100 * gain, freed.initial_rms_px, freed.final_rms_px, most));
  } else {
    cams_ = held_cams;
    points_ = held_points;
    refine_principal_point_ = false;
    notes_.push_back(fmt::format(
        "principal points held where they started: freed, they fit the samples only {:.1f}% "
        "better ({:.3f} -> {:.3f} px RMS; {:.0f}% or more refines them)",
        100 * std::max(0.0, gain), freed.initial_rms_px, freed.final_rms_px,
        100 * WandCalibrationOptions::kPrincipalPointGain));
  }
}

double WandSolver::rejectOutliers() {
  std::vector<double> errors;
  for (int sp = 0; sp < m_; ++sp) {
    if (!valid_[sp]) continue;
    for (int c = 0; c < n_; ++c) {
      if (!agree_[sp][c]) continue;
      Eigen::Vector2d pixel;
      if (projectBundle(cams_[c], points_[sp], pixel))
        errors.push_back((pixel - s_.pixel(sp, c)).norm());
    }
  }
  if (errors.empty()) return o_.min_outlier_threshold_px;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  // The median of a 2-D Gaussian error's length is sigma·sqrt(2 ln 2).
  const double sigma = errors[errors.size() / 2] / std::sqrt(2 * std::log(2.0));
  const double threshold = std::max(o_.min_outlier_threshold_px, 4 * sigma);
  // Every observation of a registered camera is judged again, so that one wrongly dropped early
  // (when the cameras were rough) comes back; the point is re-triangulated from those that agree.
  for (int sp = 0; sp < m_; ++sp) {
    std::vector<int> views;
    if (valid_[sp]) {
      for (int c = 0; c < n_; ++c) {
        agree_[sp][c] = 0;
        if (!registered_[c] || !s_.has(sp, c)) continue;
        Eigen::Vector2d pixel;
        if (projectBundle(cams_[c], points_[sp], pixel) &&
            (pixel - s_.pixel(sp, c)).norm() <= threshold)
          agree_[sp][c] = 1;
      }
    }
    int agreeing = 0;
    for (int c = 0; c < n_; ++c) agreeing += agree_[sp][c];
    if (agreeing < 2) triangulate(sp, threshold);
  }
  return threshold;
}

void WandSolver::alignGauge(WandCalibrationResult& result) const {
  Similarity g;
  bool scaled = false;
  if (o_.wand_length_m > 0) {
    if (s_.wand_pairs.empty())
      throw Error("a wand length was given but the session lists no wand pairs (pair lines)");
    std::vector<double> ratios;
    for (const auto& [a, b] : s_.wand_pairs) {
      if (a < m_ && b < m_ && valid_[a] && valid_[b])
        ratios.push_back(o_.wand_length_m / (points_[a] - points_[b]).norm());
    }
    if (ratios.size() < 3) {
      throw Error(
          fmt::format("only {} of the session's {} wand pairs were reconstructed; 3 are "
                      "needed for the scale",
                      ratios.size(), s_.wand_pairs.size()));
    }
    std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
    g.scale = ratios[ratios.size() / 2];
    scaled = true;
  }
  std::vector<Eigen::Vector3d> from, to;
  for (const FloorMark& mark : s_.floor_marks) {
    if (mark.sample < m_ && valid_[mark.sample]) {
      from.push_back(g.scale * points_[mark.sample]);
      to.push_back(mark.world_m);
    } else {
      result.report.notes.push_back(fmt::format(
          "floor mark of sample {} was not reconstructed (seen by too few cameras)", mark.sample));
    }
  }
  if (from.size() >= 3) {
    if (nearlyOnALine(to))
      throw Error(fmt::format(
          "the {} floor marks lie (nearly) on a line, which leaves the floor's tilt about it "
          "undetermined: place at least three that form a wide triangle",
          to.size()));
    const Similarity f = alignPoints(from, to, !scaled);
    g = Similarity{f.scale * g.scale, f.R, f.t};
    double sum = 0;
    for (size_t i = 0; i < from.size(); ++i) sum += (f.apply(from[i]) - to[i]).squaredNorm();
    result.report.notes.push_back(
        fmt::format("{} floor marks fix the floor{}: they fit to {:.1f} mm RMS", from.size(),
                    scaled ? "" : " and the scale", 1e3 * std::sqrt(sum / from.size())));
    scaled = true;
  } else {
    result.report.notes.push_back(fmt::format(
        "fewer than 3 floor marks reconstructed: the frame is camera {}'s{}", name(fixed_),
        scaled ? ""
               : fmt::format(" and the unit the distance from it to camera {}", name(scale_))));
  }
  result.report.metric = scaled;
  result.rig = g.apply(result.rig);
  // Floor marks put the world where the initial rig had it, so its stage box still holds;
  // without them the world is a camera's and the box is left to the cameras' views.
  if (o_.initial_rig && o_.initial_rig->stage()) {
    if (from.size() >= 3) {
      result.rig.setStage(o_.initial_rig->stage());
    } else {
      result.report.notes.push_back(
          "the initial rig's stage box is left out: without 3 floor marks the world is not the "
          "stage's; give the new rig file its `stage` again");
    }
  }
  for (Eigen::Vector3d& p : result.points_m) p = g.apply(p);
}

Rig WandSolver::makeRig(std::vector<std::string>& notes) const {
  std::vector<Camera> cameras;
  for (int c = 0; c < n_; ++c) {
    const BundleCamera& k = cams_[c];
    const WandCamera& wc = s_.cameras()[c];
    cameras.emplace_back(wc.name, wc.width, wc.height,
                         Intrinsics{k.focal_px, k.focal_px, k.cx, k.cy, 0},
                         Distortion{k.k1, k.k2, 0, 0, 0}, rotationOf(k), k.translation);
  }
  if (!o_.initial_rig) return Rig(std::move(cameras), dealCamerasToNodes(n_, o_.cameras_per_node));
  // The initial rig's camera order and nodes (with their hosts) are kept for the cameras the
  // session has; its cameras the session lacks are left out, and the session's cameras it lacks
  // go to new nodes after its own. The report's notes say what changed.
  const Rig& initial = *o_.initial_rig;
  std::vector<Camera> ordered;
  std::vector<int> place(initial.cameraCount(), -1);  // initial index -> index in `ordered`
  std::vector<uint8_t> placed(n_, 0);
  std::string missing, fresh_names;
  for (int i = 0; i < initial.cameraCount(); ++i) {
    const std::optional<int> c = s_.findCamera(initial.camera(i).name());
    if (!c) {
      missing += (missing.empty() ? "" : ", ") + initial.camera(i).name();
      continue;
    }
    place[i] = static_cast<int>(ordered.size());
    ordered.push_back(cameras[*c]);
    placed[*c] = 1;
  }
  std::vector<RigNode> nodes;
  for (const RigNode& node : initial.nodes()) {
    RigNode kept{node.name, node.host, {}};
    for (int i : node.cameras)
      if (place[i] >= 0) kept.cameras.push_back(place[i]);
    if (kept.cameras.empty()) {
      notes.push_back(
          fmt::format("node {} has none of its cameras in the session: left out", node.name));
      continue;
    }
    nodes.push_back(std::move(kept));
  }
  std::vector<int> fresh;
  for (int c = 0; c < n_; ++c) {
    if (placed[c]) continue;
    fresh.push_back(static_cast<int>(ordered.size()));
    ordered.push_back(cameras[c]);
    fresh_names += (fresh_names.empty() ? "" : ", ") + cameras[c].name();
  }
  if (!fresh.empty()) {
    std::string new_nodes;
    int number = 1;
    for (RigNode& node : dealCamerasToNodes(static_cast<int>(fresh.size()), o_.cameras_per_node)) {
      const auto taken = [&](const std::string& name) {
        return std::any_of(nodes.begin(), nodes.end(),
                           [&](const RigNode& other) { return other.name == name; });
      };
      while (taken("node" + std::to_string(number))) ++number;
      node.name = "node" + std::to_string(number);
      for (int& c : node.cameras) c = fresh[c];
      new_nodes += (new_nodes.empty() ? "" : ", ") + node.name;
      nodes.push_back(std::move(node));
    }
    notes.push_back(
        fmt::format("cameras not in the initial rig ({}) are on new nodes ({}): give them hosts",
                    fresh_names, new_nodes));
  }
  if (!missing.empty())
    notes.push_back(
        fmt::format("cameras of the initial rig not in the session are left out: {}", missing));
  return Rig(std::move(ordered), std::move(nodes));
}

WandCalibrationResult WandSolver::solve() {
  const auto start = std::chrono::steady_clock::now();
  checkSession();
  initialIntrinsics();
  points_.assign(m_, Eigen::Vector3d::Zero());
  valid_.assign(m_, 0);
  agree_.assign(m_, std::vector<uint8_t>(n_, 0));
  report("init", 0, n_);
  initialPair();
  const double init_threshold = 2 * o_.ransac_threshold_px;
  triangulateAll(init_threshold);
  int count = 2;
  report("resection", count, n_);
  while (count < n_) {
    int next = -1, best = -1;
    for (int c = 0; c < n_; ++c) {
      if (registered_[c]) continue;
      int shared = 0;
      for (int sp = 0; sp < m_; ++sp) shared += valid_[sp] && s_.has(sp, c);
      if (shared > best) best = shared, next = c;
    }
    resect(next);
    ++count;
    triangulateAll(init_threshold);
    // Keep the growing reconstruction tight, so that the next cameras resect against good points.
    if (count >= 4 && (count % 3 == 0 || count == n_)) {
      bundle(count >= 5, false, 2.0, 25);
      triangulateAll(init_threshold);
    }
    report("resection", count, n_);
  }
  // Robust adjustment of everything, then outlier rejection and plain least squares.
  const int rounds = 3;
  report("bundle", 0, rounds + 1);
  bundle(true, false, 2.0, 50);
  rejectOutliers();
  bundle(true, o_.refine_distortion, 1.0, 100);
  report("bundle", 1, rounds + 1);
  for (int round = 0; round < rounds; ++round) {
    rejectOutliers();
    bundle(true, o_.refine_distortion, 0, 100);
    report("bundle", round + 2, rounds + 1);
  }
  if (o_.principal_point == WandCalibrationOptions::PrincipalPoint::kAuto) decidePrincipalPoints();

  WandCalibrationResult result;
  std::vector<std::string> rig_notes;
  result.rig = makeRig(rig_notes);
  result.points_m = points_;
  result.point_valid = valid_;
  result.inlier = agree_;
  alignGauge(result);

  // The report, from the final cameras (the gauge moves do not change reprojections).
  CalibrationReport& r = result.report;
  r.method = "wand";
  r.samples = m_;
  for (const std::string& note : notes_) r.notes.push_back(note);
  for (const std::string& note : rig_notes) r.notes.push_back(note);
  for (const Camera& cam : result.rig.cameras()) {
    const int c = *s_.findCamera(cam.name());
    std::vector<Eigen::Vector2d> observed, residuals;
    const int seen = s_.observationCount(c);
    for (int sp = 0; sp < m_; ++sp) {
      if (!valid_[sp] || !agree_[sp][c]) continue;
      Eigen::Vector2d pixel;
      if (!projectBundle(cams_[c], points_[sp], pixel)) continue;
      observed.push_back(s_.pixel(sp, c));
      residuals.push_back(pixel - s_.pixel(sp, c));
    }
    result.outliers_rejected += seen - static_cast<int>(observed.size());
    r.cameras.push_back(makeCameraReport(cam, observed, residuals, seen));
  }
  finishReport(r);
  int reconstructed = 0;
  for (uint8_t v : valid_) reconstructed += v;
  r.notes.push_back(
      fmt::format("{} of {} samples reconstructed; {} observations rejected as outliers",
                  reconstructed, m_, result.outliers_rejected));
  r.solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

WandCalibrationResult calibrateWand(const WandSession& session,
                                    const WandCalibrationOptions& options) {
  return WandSolver(session, options).solve();
}

}  // namespace lumistage
