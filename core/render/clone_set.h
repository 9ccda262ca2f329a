#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/camera.h"

namespace lumistage {

// A copy of the actor placed elsewhere on the stage: the actor's rendering moved by a rigid
// transform (a turn about the vertical through a pivot, the actor's place, then a shift on the
// floor).
struct Clone {
  int id = 0;
  std::string name;
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero();  // on the floor
  double yaw_rad = 0;                                  // about the vertical
  // Actor space (the real actor's place) -> stage, turning about the vertical through `pivot`.
  Eigen::Affine3d transform(const Eigen::Vector3d& pivot = Eigen::Vector3d::Zero()) const;
};

// The clones of the actor the director placed: added, moved, turned and removed by id. Kept
// minimal, as a list of rigid transforms, for the renderer to draw and the studio to edit.
// A set holds at most kMaxClones, each within kReachM of the actor on either axis: what the
// nodes take in a view (MessageLimits::max_clones; offsets within 1000 m), so that no edit makes
// the nodes refuse the view and the director's picture freeze.
class CloneSet {
 public:
  static constexpr int kMaxClones = 64;
  static constexpr double kReachM = 20.0;
  // Returns the new id, or 0 when the set holds kMaxClones already. Offsets are clamped to
  // +-kReachM on each axis, here and when moved.
  int add(const Eigen::Vector2d& offset_m, double yaw_rad = 0);
  bool remove(int id);
  bool moveTo(int id, const Eigen::Vector2d& offset_m);
  bool moveBy(int id, const Eigen::Vector2d& delta_m);
  bool rotateBy(int id, double yaw_rad);
  void clear() { clones_.clear(); }
  const Clone* find(int id) const;
  const std::vector<Clone>& clones() const { return clones_; }
  std::vector<Eigen::Affine3d> transforms(
      const Eigen::Vector3d& pivot = Eigen::Vector3d::Zero()) const;
  // The clone whose copy of `actor_position` (a floor point, the pivot) is nearest `pixel` in
  // `view`, within `radius_px`.
  std::optional<int> pick(const Camera& view, const Eigen::Vector2d& pixel,
                          const Eigen::Vector3d& actor_position, double radius_px = 40) const;

 private:
  Clone* findMutable(int id);
  std::vector<Clone> clones_;
  int next_id_ = 1;
};

// Where a ray (e.g. through the cursor) meets the floor z = 0; empty when it never does.
std::optional<Eigen::Vector3d> floorPoint(const Ray& ray);

}  // namespace lumistage
