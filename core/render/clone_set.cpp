#include "core/render/clone_set.h"

#include <algorithm>
#include <cmath>

#include "core/net/message_types.h"

namespace lumistage {

// The studio's clone editor holds no more clones than the nodes take in a view.
static_assert(CloneSet::kMaxClones == MessageLimits{}.max_clones);

Eigen::Affine3d Clone::transform(const Eigen::Vector3d& pivot) const {
  return Eigen::Translation3d(pivot + Eigen::Vector3d(offset_m.x(), offset_m.y(), 0)) *
         Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(-pivot);
}

namespace {
Eigen::Vector2d withinReach(const Eigen::Vector2d& offset_m) {
  // NaN (a floor point of a ray parallel to the floor) becomes 0.
  const auto clamp = [](double v) {
    return std::isnan(v) ? 0.0 : std::clamp(v, -CloneSet::kReachM, CloneSet::kReachM);
  };
  return {clamp(offset_m.x()), clamp(offset_m.y())};
}
}  // namespace

int CloneSet::add(const Eigen::Vector2d& offset_m, double yaw_rad) {
  if (int(clones_.size()) >= kMaxClones) return 0;
  Clone c;
  c.id = next_id_++;
  c.name = "clone " + std::to_string(c.id);
  c.offset_m = withinReach(offset_m);
  c.yaw_rad = yaw_rad;
  clones_.push_back(c);
  return c.id;
}

bool CloneSet::remove(int id) {
  const auto it =
      std::find_if(clones_.begin(), clones_.end(), [id](const Clone& c) { return c.id == id; });
  if (it == clones_.end()) return false;
  clones_.erase(it);
  return true;
}

Clone* CloneSet::findMutable(int id) {
  for (Clone& c : clones_) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

const Clone* CloneSet::find(int id) const {
  for (const Clone& c : clones_) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

bool CloneSet::moveTo(int id, const Eigen::Vector2d& offset_m) {
  Clone* c = findMutable(id);
  if (c) c->offset_m = withinReach(offset_m);
  return c != nullptr;
}

bool CloneSet::moveBy(int id, const Eigen::Vector2d& delta_m) {
  Clone* c = findMutable(id);
  if (c) c->offset_m = withinReach(c->offset_m + delta_m);
  return c != nullptr;
}

bool CloneSet::rotateBy(int id, double yaw_rad) {
  Clone* c = findMutable(id);
  if (c) c->yaw_rad = std::remainder(c->yaw_rad + yaw_rad, 2 * M_PI);
  return c != nullptr;
}

std::vector<Eigen::Affine3d> CloneSet::transforms(const Eigen::Vector3d& pivot) const {
  std::vector<Eigen::Affine3d> out;
  for (const Clone& c : clones_) out.push_back(c.transform(pivot));
  return out;
}

std::optional<int> CloneSet::pick(const Camera& view, const Eigen::Vector2d& pixel,
                                  const Eigen::Vector3d& actor_position, double radius_px) const {
  std::optional<int> best;
  double best_d = radius_px;
  for (const Clone& c : clones_) {
    const std::optional<Eigen::Vector2d> p =
        view.project(c.transform(actor_position) * actor_position);
    if (!p) continue;
    const double d = (*p - pixel).norm();
    if (d <= best_d) {
      best_d = d;
      best = c.id;
    }
  }
  return best;
}

std::optional<Eigen::Vector3d> floorPoint(const Ray& ray) {
  if (std::abs(ray.direction.z()) < 1e-9) return std::nullopt;
  const double s = -ray.origin.z() / ray.direction.z();
  if (s <= 0) return std::nullopt;
  return ray.origin + s * ray.direction;
}

}  // namespace lumistage
