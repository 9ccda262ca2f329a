#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/imaging/clean_plate.h"
#include "core/refine/refine_config.h"

namespace lumistage {

// Point-to-surface distances against a triangle mesh, through a uniform grid of triangles.
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const TriangleMesh& mesh, double cell_m = 0.05);
  // The distance from p to the nearest point of any triangle.
  double distance(const Eigen::Vector3d& p) const;

 private:
  double bruteForce(const Eigen::Vector3d& p) const;
  double toTriangle(const Eigen::Vector3d& p, int triangle) const;

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  Eigen::Vector3d origin_;
  double cell_;
  Eigen::Vector3i size_;
  std::vector<int> cell_start_, cell_triangles_;
  mutable std::vector<int> stamp_;
  mutable int stamp_now_ = 0;
};

struct SurfaceError {
  double mean_mm = 0, p95_mm = 0, max_mm = 0;
  int points = 0;
};

// Distances (mm) from every column of `points` to the surface: mean, 95th percentile and max.
SurfaceError surfaceError(const Eigen::Matrix3Xf& points, const SurfaceDistance& surface);
// Pools several frames' distances: the mean over all points, the p95 over all points.
SurfaceError poolSurfaceErrors(const std::vector<std::vector<double>>& distances_mm);
void surfaceDistancesMm(const Eigen::Matrix3Xf& points, const SurfaceDistance& surface,
                        std::vector<double>& out);

// What the refinement could reach on a mesh at best: each vertex moved along its normal to the
// point of [-t_inward_m, t_max_m] (the refinement's range, RefineConfig) nearest the surface
// (searched in steps of step_m), as if every offset were chosen knowing the truth. Rendered, it
// splits what the refinement's choice loses from what the mesh and the pose cannot represent
// (docs/eval-report.md, loo_psnr_db_best_offsets). `out` is resized only when its size differs.
void nearestOffsetsAlongNormals(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                                const SurfaceDistance& surface, double t_inward_m, double t_max_m,
                                double step_m, Eigen::Matrix3Xf& out);

// The refinement measured on a virtual-studio session: per frame, the generic human posed by a
// fit to the true joints (truth/joints.csv; one bone-length scale) is the unrefined mesh; each
// node of the rig samples its own cameras (green-screen keyers learnt from the frame's image
// borders), the studio combines the nodes' statistics and refines. Distances are measured from
// the mesh's vertices to the true surface's triangles (truth/surface), in mm.
struct SurfaceEvaluation {
  SurfaceError unrefined, refined;  // pooled over the frames
  std::vector<SurfaceError> unrefined_per_frame, refined_per_frame;
  double joint_fit_rms_mm = 0;           // mean over frames of the pose fit's joint rms
  double statistics_bytes_per_node = 0;  // mean encoded size per node and frame
  // Shimmer: the mean change of a vertex's chosen offset from one evaluated frame to the next.
  double offset_change_mm = 0;
  int frames = 0;
};

struct SurfaceEvaluationOptions {
  RefineConfig refine;
  int first_frame = 0;
  int max_frames = 0;  // 0: all
  int frame_step = 1;
  const CameraPlates* plates = nullptr;  // the cameras' clean plates; null: sessionPlates
};

// Throws Error when the session has no truth or the files are malformed.
SurfaceEvaluation evaluateSurface(const std::filesystem::path& session, const SkinnedMesh& generic,
                                  const SurfaceEvaluationOptions& options = {});

}  // namespace lumistage
