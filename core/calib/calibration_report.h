#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/geometry/camera.h"

namespace lumistage {

// How well one camera is calibrated: the reprojection error of the samples it kept, how many it
// rejected, and how much of its image the samples covered (a lens model is only known where it
// was sampled). The calibration panel shows these; the file format is in docs/calibration.md.
struct CameraCalibrationReport {
  std::string name;
  int width = 0, height = 0;
  int observations = 0;  // samples the camera saw
  int inliers = 0;       // of those, used in the solution
  double rms_px = 0;     // reprojection RMS over the inliers
  double max_px = 0;
  // Inlier counts in a grid of coverage_cols x coverage_rows cells over the image, rows top first.
  int coverage_cols = 0, coverage_rows = 0;
  std::vector<int> coverage;
  double coverage_fraction = 0;  // cells with at least one inlier
  double focal_px = 0, cx = 0, cy = 0, k1 = 0, k2 = 0;
};

struct CalibrationReport {
  std::string method;  // "wand" or "board"
  int samples = 0;     // wand samples, or board views
  double rms_px = 0;   // over every inlier of every camera
  double solve_s = 0;
  bool metric = false;  // whether the scale is known (wand length, floor marks or board)
  std::vector<std::string> notes;
  std::vector<CameraCalibrationReport> cameras;
};

// Residuals and coverage of a camera from its inlier pixels (observed) and their reprojection
// errors; observations counts the rejected ones too.
CameraCalibrationReport makeCameraReport(const Camera& camera,
                                         const std::vector<Eigen::Vector2d>& observed,
                                         const std::vector<Eigen::Vector2d>& residuals,
                                         int observations, int coverage_cols = 16,
                                         int coverage_rows = 12);
void finishReport(CalibrationReport& report);  // overall RMS from the cameras'

std::string formatCalibrationReport(const CalibrationReport& report);  // YAML
void saveCalibrationReport(const CalibrationReport& report, const std::filesystem::path& path);
// Back from the file (for the studio's calibration panel); Error with file:line: key for anything
// malformed.
CalibrationReport loadCalibrationReport(const std::filesystem::path& path);
CalibrationReport parseCalibrationReport(std::string_view yaml_text, std::string_view source_name);
// Where `lumistage calibrate` writes a rig's report unless told otherwise, and where the studio
// looks for it: beside the rig file, its name the rig's with ".calibration.yaml" for its
// extension (stage.yaml: stage.calibration.yaml).
std::filesystem::path calibrationReportPathFor(const std::filesystem::path& rig_path);
// A table for a terminal.
std::string summarizeCalibrationReport(const CalibrationReport& report);

}  // namespace lumistage
