#include "core/calib/calibration_report.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/yaml_reader.h"

namespace lumistage {

CameraCalibrationReport makeCameraReport(const Camera& camera,
                                         const std::vector<Eigen::Vector2d>& observed,
                                         const std::vector<Eigen::Vector2d>& residuals,
                                         int observations, int coverage_cols, int coverage_rows) {
  CameraCalibrationReport r;
  r.name = camera.name();
  r.width = camera.width(), r.height = camera.height();
  r.observations = observations;
  r.inliers = static_cast<int>(observed.size());
  double sum = 0;
  for (const Eigen::Vector2d& e : residuals) {
    sum += e.squaredNorm();
    r.max_px = std::max(r.max_px, e.norm());
  }
  r.rms_px = residuals.empty() ? 0 : std::sqrt(sum / residuals.size());
  r.coverage_cols = coverage_cols, r.coverage_rows = coverage_rows;
  r.coverage.assign(static_cast<size_t>(coverage_cols) * coverage_rows, 0);
  for (const Eigen::Vector2d& p : observed) {
    const int col = std::clamp(static_cast<int>((p.x() + 0.5) * coverage_cols / camera.width()), 0,
                               coverage_cols - 1);
    const int row = std::clamp(static_cast<int>((p.y() + 0.5) * coverage_rows / camera.height()), 0,
                               coverage_rows - 1);
    ++r.coverage[static_cast<size_t>(row) * coverage_cols + col];
  }
  int covered = 0;
  for (int n : r.coverage) covered += n > 0;
  r.coverage_fraction = r.coverage.empty() ? 0 : double(covered) / r.coverage.size();
  const Intrinsics& k = camera.intrinsics();
  r.focal_px = k.fx, r.cx = k.cx, r.cy = k.cy;
  r.k1 = camera.distortion().k1, r.k2 = camera.distortion().k2;
  return r;
}

void finishReport(CalibrationReport& report) {
  double sum = 0;
  int n = 0;
  for (const CameraCalibrationReport& c : report.cameras) {
    sum += c.rms_px * c.rms_px * c.inliers;
    n += c.inliers;
  }
  report.rms_px = n ? std::sqrt(sum / n) : 0;
}

namespace {

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string formatCalibrationReport(const CalibrationReport& report) {
  std::string out = "# lumistage calibration report (docs/calibration.md)\n";
  out += fmt::format("method: {}\nsamples: {}\nrms_px: {:.4f}\nsolve_s: {:.3f}\nmetric: {}\n",
                     report.method, report.samples, report.rms_px, report.solve_s,
                     report.metric ? "true" : "false");
  out += "notes:";
  if (report.notes.empty()) out += " []";
  out += "\n";
  for (const std::string& n : report.notes) out += "  - " + quoted(n) + "\n";
  out += "cameras:\n";
  for (const CameraCalibrationReport& c : report.cameras) {
    out += fmt::format("  - name: {}\n    image_size: [{}, {}]\n", c.name, c.width, c.height);
    out += fmt::format("    observations: {}\n    inliers: {}\n", c.observations, c.inliers);
    out += fmt::format("    rms_px: {:.4f}\n    max_px: {:.4f}\n", c.rms_px, c.max_px);
    out += fmt::format("    focal_px: {:.3f}\n    principal_point_px: [{:.3f}, {:.3f}]\n",
                       c.focal_px, c.cx, c.cy);
    out += fmt::format("    k1_k2: [{:.6f}, {:.6f}]\n", c.k1, c.k2);
    out += fmt::format("    coverage_fraction: {:.4f}\n    coverage_grid: [{}, {}]\n",
                       c.coverage_fraction, c.coverage_cols, c.coverage_rows);
    out += "    coverage:\n";
    for (int row = 0; row < c.coverage_rows; ++row) {
      std::string line;
      for (int col = 0; col < c.coverage_cols; ++col) {
        line += (col ? ", " : "") +
                std::to_string(c.coverage[static_cast<size_t>(row) * c.coverage_cols + col]);
      }
      out += "      - [" + line + "]\n";
    }
  }
  return out;
}

void saveCalibrationReport(const CalibrationReport& report, const std::filesystem::path& path) {
  writeFileAtomically(path, formatCalibrationReport(report));
}

CalibrationReport parseCalibrationReport(std::string_view yaml_text, std::string_view source_name) {
  const YamlReader y{std::string(source_name)};
  const YAML::Node root = y.parseDocument(yaml_text);
  y.requireMap(root, "");
  CalibrationReport r;
  r.method = y.string(y.required(root, "", "method", "wand or board"), "method");
  r.samples = y.integer(y.required(root, "", "samples", "a count"), "samples");
  r.rms_px = y.number(y.required(root, "", "rms_px", "pixels"), "rms_px");
  if (root["solve_s"]) r.solve_s = y.number(root["solve_s"], "solve_s");
  if (root["metric"]) {
    try {
      r.metric = root["metric"].as<bool>();
    } catch (const YAML::Exception&) {
      y.fail(root["metric"], "metric", "expected true or false");
    }
  }
  if (const YAML::Node notes = root["notes"]) {
    y.requireSequence(notes, "notes");
    for (size_t i = 0; i < notes.size(); ++i)
      r.notes.push_back(y.string(notes[i], YamlReader::item("notes", i)));
  }
  const YAML::Node cameras = y.required(root, "", "cameras", "a sequence of cameras");
  y.requireSequence(cameras, "cameras");
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string key = YamlReader::item("cameras", i);
    const YAML::Node c = cameras[i];
    y.requireMap(c, key);
    auto get = [&](const char* name) { return y.required(c, key, name, "a value"); };
    auto at = [&](const char* name) { return YamlReader::child(key, name); };
    CameraCalibrationReport cr;
    cr.name = y.string(get("name"), at("name"));
    const YAML::Node size = get("image_size");
    y.requireSequence(size, at("image_size"), 2);
    cr.width = y.integer(size[0], at("image_size")),
    cr.height = y.integer(size[1], at("image_size"));
    cr.observations = y.integer(get("observations"), at("observations"));
    cr.inliers = y.integer(get("inliers"), at("inliers"));
    cr.rms_px = y.number(get("rms_px"), at("rms_px"));
    cr.max_px = y.number(get("max_px"), at("max_px"));
    cr.focal_px = y.number(get("focal_px"), at("focal_px"));
    const YAML::Node pp = get("principal_point_px");
    y.requireSequence(pp, at("principal_point_px"), 2);
    cr.cx = y.number(pp[0], at("principal_point_px")),
    cr.cy = y.number(pp[1], at("principal_point_px"));
    const YAML::Node k = get("k1_k2");
    y.requireSequence(k, at("k1_k2"), 2);
    cr.k1 = y.number(k[0], at("k1_k2")), cr.k2 = y.number(k[1], at("k1_k2"));
    cr.coverage_fraction = y.number(get("coverage_fraction"), at("coverage_fraction"));
    const YAML::Node grid = get("coverage_grid");
    y.requireSequence(grid, at("coverage_grid"), 2);
    cr.coverage_cols = y.integer(grid[0], at("coverage_grid"));
    cr.coverage_rows = y.integer(grid[1], at("coverage_grid"));
    if (cr.coverage_cols <= 0 || cr.coverage_rows <= 0 || cr.coverage_cols > 1000 ||
        cr.coverage_rows > 1000)
      y.fail(grid, at("coverage_grid"), "expected two positive sizes up to 1000");
    const YAML::Node rows = get("coverage");
    y.requireSequence(rows, at("coverage"), cr.coverage_rows);
    for (int row = 0; row < cr.coverage_rows; ++row) {
      const std::string row_key = YamlReader::item(at("coverage"), row);
      y.requireSequence(rows[row], row_key, cr.coverage_cols);
      for (int col = 0; col < cr.coverage_cols; ++col)
        cr.coverage.push_back(y.integer(rows[row][col], row_key));
    }
    r.cameras.push_back(std::move(cr));
  }
  return r;
}

CalibrationReport loadCalibrationReport(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the calibration report");
  std::ostringstream text;
  text << in.rdbuf();
  return parseCalibrationReport(text.str(), path.string());
}

std::string summarizeCalibrationReport(const CalibrationReport& report) {
  std::string out = fmt::format("{} calibration: {} samples, RMS {:.3f} px, {:.2f} s{}\n",
                                report.method, report.samples, report.rms_px, report.solve_s,
                                report.metric ? "" : " (scale unknown)");
  out += fmt::format("{:<10} {:>6} {:>7} {:>8} {:>8} {:>9} {:>9}\n", "camera", "seen", "inliers",
                     "rms px", "max px", "coverage", "focal px");
  for (const CameraCalibrationReport& c : report.cameras) {
    out += fmt::format("{:<10} {:>6} {:>7} {:>8.3f} {:>8.3f} {:>8.0f}% {:>9.1f}\n", c.name,
                       c.observations, c.inliers, c.rms_px, c.max_px, 100 * c.coverage_fraction,
                       c.focal_px);
  }
  for (const std::string& n : report.notes) out += "note: " + n + "\n";
  return out;
}

std::filesystem::path calibrationReportPathFor(const std::filesystem::path& rig_path) {
  std::filesystem::path report = rig_path;
  report.replace_extension(".calibration.yaml");
  return report;
}

}  // namespace lumistage
