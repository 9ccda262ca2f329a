#include "core/calib/wand_simulation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

namespace lumistage {

SimulatedWandSession simulateWandSession(const Rig& rig, const WandSimulationOptions& options) {
  std::vector<WandCamera> cameras;
  for (const Camera& c : rig.cameras()) cameras.push_back({c.name(), c.width(), c.height()});
  SimulatedWandSession sim;
  sim.session = WandSession(cameras, 0);
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  const Eigen::Vector3d lo = options.volume_min_m, hi = options.volume_max_m;
  auto randomDirection = [&] {
    Eigen::Vector3d d(gauss(rng), gauss(rng), gauss(rng));
    return Eigen::Vector3d(d.normalized());
  };
  std::vector<Eigen::Vector3d> points;
  std::vector<uint8_t> is_mark;
  Eigen::Vector3d p = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
  Eigen::Vector3d velocity = options.step_m * randomDirection();
  while (static_cast<int>(points.size()) < options.samples) {
    points.push_back(p);
    is_mark.push_back(0);
    if (options.wand_length_m > 0 && static_cast<int>(points.size()) < options.samples) {
      sim.session.wand_pairs.emplace_back(static_cast<int>(points.size()) - 1,
                                          static_cast<int>(points.size()));
      points.push_back(p + options.wand_length_m * randomDirection());
      is_mark.push_back(0);
    }
    // A smooth wave: the velocity turns gradually; the path bounces off the volume's walls.
    velocity = options.step_m * (velocity / options.step_m + 0.6 * randomDirection()).normalized();
    p += velocity;
    for (int i = 0; i < 3; ++i) {
      if (p[i] < lo[i] || p[i] > hi[i]) {
        velocity[i] = -velocity[i];
        p[i] = std::clamp(p[i], lo[i], hi[i]);
      }
    }
  }
  for (const Eigen::Vector3d& m : options.floor_marks_m) {
    sim.session.floor_marks.push_back({static_cast<int>(points.size()), m});
    points.push_back(m);
    is_mark.push_back(1);
  }

  sim.session.addSamples(static_cast<int>(points.size()));
  sim.points_m = points;
  sim.outlier.assign(points.size(), std::vector<uint8_t>(rig.cameraCount(), 0));
  for (size_t s = 0; s < points.size(); ++s) {
    for (int c = 0; c < rig.cameraCount(); ++c) {
      const Camera& cam = rig.camera(c);
      const std::optional<Eigen::Vector2d> pixel = cam.project(points[s]);
      if (!pixel || !cam.inImage(*pixel)) continue;
      if (!is_mark[s] && unit(rng) < options.dropout) continue;
      Eigen::Vector2d observed =
          *pixel + options.noise_px * Eigen::Vector2d(gauss(rng), gauss(rng));
      if (!is_mark[s] && unit(rng) < options.outlier_fraction) {
        observed = Eigen::Vector2d(unit(rng) * (cam.width() - 1), unit(rng) * (cam.height() - 1));
        sim.outlier[s][c] = 1;
      }
      if (!cam.inImage(observed)) continue;
      sim.session.set(static_cast<int>(s), c, observed);
    }
  }
  return sim;
}

void renderWandFrame(const Camera& camera, const std::vector<Eigen::Vector2d>& spots_px,
                     Image& out) {
  out.resize(PixelFormat::kMono8, camera.width(), camera.height());
  std::fill(out.pixels.begin(), out.pixels.end(), uint8_t{10});
  for (const Eigen::Vector2d& spot : spots_px) {
    const int x0 = std::max(0, static_cast<int>(spot.x()) - 7);
    const int x1 = std::min(camera.width(), static_cast<int>(spot.x()) + 8);
    const int y0 = std::max(0, static_cast<int>(spot.y()) - 7);
    const int y1 = std::min(camera.height(), static_cast<int>(spot.y()) + 8);
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const double d2 = (Eigen::Vector2d(x, y) - spot).squaredNorm();
        uint8_t& v = out.pixels[static_cast<size_t>(y) * camera.width() + x];
        v = static_cast<uint8_t>(std::min(255.0, v + 240 * std::exp(-d2 / 8.0)));
      }
    }
  }
}

}  // namespace lumistage
