#include "core/geometry/rig_import.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <sstream>
#include <stdexcept>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/names.h"
#include "core/geometry/file_storage_matrix.h"
#include "core/geometry/file_storage_nesting.h"
#include "core/geometry/projection_matrix.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/rotation.h"

namespace lumistage {

Rig assembleImportedRig(std::vector<Camera> cameras, const RigImportOptions& options,
                        const std::string& source) {
  if (cameras.empty()) throw Error(source + ": no cameras found");
  try {
    std::vector<RigNode> nodes =
        dealCamerasToNodes(static_cast<int>(cameras.size()), options.cameras_per_node);
    return Rig(std::move(cameras), std::move(nodes));
  } catch (const std::invalid_argument& e) {
    throw Error(source + ": " + e.what());
  }
}

namespace {

namespace fs = std::filesystem;

// ---- OpenCV FileStorage ----------------------------------------------------------------------

cv::FileNode firstOf(const cv::FileNode& camera, std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    cv::FileNode node = camera[key];
    if (!node.empty()) return node;
  }
  return {};
}

Eigen::MatrixXd readMatrix(const cv::FileNode& node, const std::string& where) {
  const cv::Mat m = readFileStorageMatrix(node, where);
  if (m.empty()) throw Error(where + ": expected a matrix, got nothing readable");
  Eigen::MatrixXd out;
  cv::cv2eigen(m, out);
  if (!out.allFinite()) throw Error(where + ": matrix has non-finite entries");
  return out;
}

int readPositiveInt(const cv::FileNode& node, const std::string& where) {
  if (node.empty() || !node.isInt()) throw Error(where + ": expected a whole number of pixels");
  const int value = static_cast<int>(node);
  if (value <= 0) throw Error(where + ": expected a positive number, got " + std::to_string(value));
  return value;
}

Camera readOpenCvCamera(const cv::FileNode& node, int index, const std::string& source) {
  std::string name = fmt::format("cam{:02}", index + 1);
  if (!node["name"].empty()) {
    if (!node["name"].isString())
      throw Error(fmt::format("{}: camera {}: name: expected text", source, index));
    name = static_cast<std::string>(node["name"]);
    if (!isValidName(name))
      throw Error(fmt::format("{}: camera {}: name {} is not a camera name (1-64 of A-Za-z0-9_.-)",
                              source, index, quotedInput(name)));
  }
  const std::string where = fmt::format("{}: camera {} ('{}')", source, index, name);
  auto need = [&](std::initializer_list<const char*> keys, const char* expected) {
    cv::FileNode n = firstOf(node, keys);
    if (n.empty()) {
      std::string names;
      for (const char* k : keys) names += (names.empty() ? "'" : " or '") + std::string(k) + "'";
      throw Error(where + ": missing key " + names + ": expected " + expected);
    }
    return n;
  };

  const Eigen::MatrixXd K =
      readMatrix(need({"camera_matrix", "cameraMatrix", "K"}, "a 3x3 intrinsic matrix"),
                 where + ": camera_matrix");
  if (K.rows() != 3 || K.cols() != 3) {
    throw Error(
        fmt::format("{}: camera_matrix: expected 3x3, got {}x{}", where, K.rows(), K.cols()));
  }
  const Eigen::MatrixXd D = readMatrix(
      need({"distortion_coefficients", "dist_coeffs", "distCoeffs", "D"}, "4 to 14 coefficients"),
      where + ": distortion_coefficients");
  const Eigen::VectorXd d = D.reshaped();
  if (d.size() < 4) {
    throw Error(fmt::format(
        "{}: distortion_coefficients: expected at least 4 (k1 k2 p1 p2), got {}", where, d.size()));
  }
  for (Eigen::Index i = 5; i < d.size(); ++i) {
    if (d[i] != 0) {
      throw Error(fmt::format(
          "{}: distortion_coefficients: coefficient {} is {}; only k1 k2 p1 p2 k3 are supported "
          "(OpenCV's rational, thin-prism and tilted models are not)",
          where, i + 1, d[i]));
    }
  }
  Distortion distortion{d[0], d[1], d[2], d[3], d.size() > 4 ? d[4] : 0.0};

  int width = 0, height = 0;
  if (cv::FileNode size = node["image_size"]; !size.empty()) {
    const Eigen::MatrixXd s = readMatrix(size, where + ": image_size");
    if (s.size() != 2) throw Error(where + ": image_size: expected [width, height]");
    for (const double pixels : {s(0), s(1)}) {
      // Checked before the conversion: a double past int's range converted is undefined.
      if (!(pixels >= 1 && pixels <= 1 << 20) || pixels != std::floor(pixels))
        throw Error(where + ": image_size: expected whole numbers of pixels from 1 to 1048576");
    }
    width = static_cast<int>(s(0)), height = static_cast<int>(s(1));
  } else {
    width = readPositiveInt(need({"image_width"}, "the image width in pixels"),
                            where + ": image_width");
    height = readPositiveInt(need({"image_height"}, "the image height in pixels"),
                             where + ": image_height");
  }

  Eigen::Matrix3d R;
  if (cv::FileNode r = firstOf(node, {"R", "rotation"}); !r.empty()) {
    const Eigen::MatrixXd m = readMatrix(r, where + ": R");
    if (m.rows() != 3 || m.cols() != 3) throw Error(where + ": R: expected a 3x3 matrix");
    R = m;
  } else {
    const Eigen::MatrixXd rvec =
        readMatrix(need({"rvec", "R", "rotation"}, "a 3x3 rotation R or a Rodrigues vector rvec"),
                   where + ": rvec");
    if (rvec.size() != 3) throw Error(where + ": rvec: expected 3 numbers");
    R = rotationFromVector({rvec(0), rvec(1), rvec(2)});  // Rodrigues
  }
  const Eigen::MatrixXd T =
      readMatrix(need({"T", "tvec", "translation"}, "a translation (3 numbers, world to camera)"),
                 where + ": T");
  if (T.size() != 3) throw Error(where + ": T: expected 3 numbers");

  try {
    return Camera(name, width, height, Intrinsics::fromMatrix(K), distortion, R,
                  Eigen::Vector3d(T(0), T(1), T(2)));
  } catch (const std::invalid_argument& e) {
    throw Error(source + ": " + e.what());
  }
}

// ---- Svoboda's MultiCamSelfCal ----------------------------------------------------------------

// The trailing number of a file stem ("camera12" -> 12), or -1.
int trailingNumber(const std::string& stem) {
  size_t i = stem.size();
  while (i > 0 && std::isdigit(static_cast<unsigned char>(stem[i - 1]))) --i;
  if (i == stem.size() || stem.size() - i > 6) return -1;
  return std::stoi(stem.substr(i));
}

Eigen::Matrix<double, 3, 4> readPmat(const fs::path& file) {
  std::istringstream text(readFile(file));
  std::vector<double> values;
  std::string line;
  for (int line_number = 1; std::getline(text, line); ++line_number) {
    // Octave's save writes "# Created by Octave ...", "# name: Pmat", "# rows: 3" first; MATLAB
    // users comment with '%'.
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && (line[first] == '#' || line[first] == '%')) continue;
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      size_t used = 0;
      double value = 0;
      try {
        value = std::stod(word, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != word.size() || !std::isfinite(value)) {
        throw Error(fmt::format("{}:{}: expected a number, got {}", file.string(), line_number,
                                quotedInput(word)));
      }
      values.push_back(value);
    }
  }
  if (values.size() != 12) {
    throw Error(
        fmt::format("{}: expected 12 numbers (a 3x4 projection matrix, row by row), found {}",
                    file.string(), values.size()));
  }
  Eigen::Matrix<double, 3, 4> P;
  for (int i = 0; i < 12; ++i) P(i / 4, i % 4) = values[i];
  return P;
}

struct RadFile {
  Eigen::Matrix3d K;
  Distortion distortion;
};

RadFile readRad(const fs::path& file) {
  std::istringstream text(readFile(file));
  std::map<std::string, double> values;
  std::string line;
  for (int line_number = 1; std::getline(text, line); ++line_number) {
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    auto trim = [](std::string s) {
      const char* space = " \t\r;";
      s.erase(0, s.find_first_not_of(space));
      s.erase(s.find_last_not_of(space) + 1);
      return s;
    };
    const std::string key = trim(line.substr(0, eq));
    const std::string value = trim(line.substr(eq + 1));
    if (key == "comments") continue;
    size_t used = 0;
    double number = 0;
    try {
      number = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (value.empty() || used != value.size() || !std::isfinite(number)) {
      throw Error(fmt::format("{}:{}: {}: expected a number, got {}", file.string(), line_number,
                              key, quotedInput(value)));
    }
    values[key] = number;
  }
  auto get = [&](const std::string& key) {
    auto it = values.find(key);
    if (it == values.end()) {
      throw Error(fmt::format("{}: missing key '{}' (a .rad file has K11..K33 and kc1..kc4)",
                              file.string(), key));
    }
    return it->second;
  };
  RadFile rad;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rad.K(r, c) = get(fmt::format("K{}{}", r + 1, c + 1));
  }
  if (std::abs(rad.K.determinant()) < 1e-12) throw Error(file.string() + ": K is singular");
  rad.distortion = {get("kc1"), get("kc2"), get("kc3"), get("kc4"),
                    values.count("kc5") ? values["kc5"] : 0.0};
  return rad;
}

// Our model keeps one K for projection and distortion; MultiCamSelfCal's distortion lives in the
// .rad's K. Find the distortion in P's K that maps the same undistorted pixels to the same
// distorted pixels: the model is linear in (k1, k2, k3, p1, p2), so least squares over a grid of
// the image. Returns the fitted model and its worst residual in pixels.
std::pair<Distortion, double> refitDistortion(const Eigen::Matrix3d& K_p, const RadFile& rad,
                                              int width, int height) {
  constexpr int kGrid = 24;
  Eigen::MatrixXd A(2 * kGrid * kGrid, 5);
  Eigen::VectorXd b(2 * kGrid * kGrid);
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> samples;  // (x in P's K, true pixel)
  const Eigen::Matrix3d K_p_inv = K_p.inverse(), K_r_inv = rad.K.inverse();
  int row = 0;
  for (int gy = 0; gy < kGrid; ++gy) {
    for (int gx = 0; gx < kGrid; ++gx) {
      const Eigen::Vector3d pixel((width - 1) * gx / double(kGrid - 1),
                                  (height - 1) * gy / double(kGrid - 1), 1.0);
      const Eigen::Vector3d x_r = K_r_inv * pixel;
      const Eigen::Vector2d xd_r =
          rad.distortion.apply(Eigen::Vector2d(x_r.x(), x_r.y()) / x_r.z());
      const Eigen::Vector3d true_pixel = rad.K * Eigen::Vector3d(xd_r.x(), xd_r.y(), 1.0);
      const Eigen::Vector3d x_p = K_p_inv * pixel;
      const Eigen::Vector3d target = K_p_inv * (true_pixel / true_pixel.z());
      const double u = x_p.x() / x_p.z(), v = x_p.y() / x_p.z();
      const double r2 = u * u + v * v;
      A.row(row) << u * r2, u * r2 * r2, 2 * u * v, r2 + 2 * u * u, u * r2 * r2 * r2;
      b(row++) = target.x() / target.z() - u;
      A.row(row) << v * r2, v * r2 * r2, r2 + 2 * v * v, 2 * u * v, v * r2 * r2 * r2;
      b(row++) = target.y() / target.z() - v;
      samples.push_back({Eigen::Vector2d(u, v), true_pixel.head<2>() / true_pixel.z()});
    }
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  const Distortion fitted{c(0), c(1), c(2), c(3), c(4)};
  double worst = 0;
  for (const auto& [x, true_pixel] : samples) {
    const Eigen::Vector2d xd = fitted.apply(x);
    const Eigen::Vector3d pixel = K_p * Eigen::Vector3d(xd.x(), xd.y(), 1.0);
    worst = std::max(worst, (pixel.head<2>() - true_pixel).norm());
  }
  return {fitted, worst};
}

}  // namespace

RigImport importOpenCvRig(const fs::path& file, const RigImportOptions& options) {
  const std::string source = file.string();
  if (!fs::is_regular_file(file)) throw Error(source + ": no such file");
  checkFileStorageText(readFile(file), source);  // what OpenCV chokes on
  cv::FileStorage storage;
  try {
    if (!storage.open(source, cv::FileStorage::READ)) {
      throw Error(source + ": OpenCV cannot read it as a FileStorage file (YAML or XML)");
    }
  } catch (const cv::Exception& e) {
    throw Error(source + ": not a valid OpenCV FileStorage file: " + e.err);
  } catch (const std::exception& e) {
    // OpenCV's parsers let other exceptions through too (std::length_error on a YAML key ": 3").
    throw Error(source + ": not a valid OpenCV FileStorage file: " + e.what());
  }
  std::vector<Camera> cameras;
  try {
    const cv::FileNode list = storage["cameras"];
    if (!list.empty()) {
      if (!list.isSeq()) throw Error(source + ": cameras: expected a sequence of cameras");
      for (int i = 0; i < static_cast<int>(list.size()); ++i) {
        cameras.push_back(readOpenCvCamera(list[i], i, source));
      }
    } else {
      cameras.push_back(readOpenCvCamera(storage.root(), 0, source));
    }
  } catch (const cv::Exception& e) {
    throw Error(source + ": " + e.err);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(source + ": " + e.what());
  }
  return {assembleImportedRig(std::move(cameras), options, source), {}};
}

RigImport importSvobodaRig(const fs::path& folder, const RigImportOptions& options) {
  const std::string source = folder.string();
  if (!fs::is_directory(folder)) throw Error(source + ": no such folder");
  if (options.width <= 0 || options.height <= 0) {
    throw Error(source +
                ": MultiCamSelfCal output has no image size: give it (e.g. --image-size 1024x768)");
  }
  struct Entry {
    int number;
    std::string stem;
    fs::path pmat;
  };
  std::vector<Entry> entries;
  std::vector<fs::path> rads;
  for (const auto& item : fs::directory_iterator(folder)) {
    const std::string file = item.path().filename().string();
    constexpr std::string_view kPmat = ".Pmat.cal";
    if (file.size() > kPmat.size() && file.ends_with(kPmat)) {
      const std::string stem = file.substr(0, file.size() - kPmat.size());
      entries.push_back({trailingNumber(stem), stem, item.path()});
    } else if (item.path().extension() == ".rad") {
      rads.push_back(item.path());
    }
  }
  if (entries.empty()) {
    throw Error(source + ": no *.Pmat.cal files: expected MultiCamSelfCal's output folder");
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.number != b.number ? a.number < b.number : a.stem < b.stem;
  });

  RigImport result;
  std::vector<Camera> cameras;
  for (size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    const std::string name = isValidName(e.stem) ? e.stem : fmt::format("cam{:02}", i + 1);
    DecomposedProjection d;
    try {
      d = decomposeProjection(readPmat(e.pmat));
    } catch (const std::invalid_argument& error) {
      throw Error(e.pmat.string() + ": " + error.what());
    }
    // The .rad of this camera: same stem, else the only .rad with the same number.
    fs::path rad_path = folder / (e.stem + ".rad");
    if (!fs::exists(rad_path)) {
      rad_path.clear();
      int matches = 0;
      for (const fs::path& r : rads) {
        if (e.number >= 0 && trailingNumber(r.stem().string()) == e.number) {
          rad_path = r;
          ++matches;
        }
      }
      if (matches > 1) {
        throw Error(fmt::format("{}: several .rad files have number {}; name them like {}.rad",
                                source, e.number, e.stem));
      }
    }
    Distortion distortion;
    if (rad_path.empty()) {
      result.notes.push_back(fmt::format("{}: no .rad file, so no lens distortion", name));
    } else {
      const RadFile rad = readRad(rad_path);
      const Eigen::Matrix3d K_rad = rad.K / rad.K(2, 2);
      if ((K_rad - d.K).norm() <= 1e-9 * d.K.norm()) {
        distortion = rad.distortion;
      } else if (rad.distortion.isZero()) {
        distortion = {};
      } else {
        const auto [fitted, worst_px] = refitDistortion(d.K, rad, options.width, options.height);
        distortion = fitted;
        result.notes.push_back(fmt::format(
            "{}: {} has another K than the projection matrix; distortion refitted to P's K, "
            "worst error {:.3f} px over the image{}",
            name, rad_path.filename().string(), worst_px,
            worst_px > 0.1 ? " (large: check that the .rad belongs to this camera)" : ""));
      }
    }
    try {
      cameras.emplace_back(name, options.width, options.height, Intrinsics::fromMatrix(d.K),
                           distortion, d.R, d.t);
    } catch (const std::invalid_argument& error) {
      throw Error(e.pmat.string() + ": " + error.what());
    }
  }
  result.rig = assembleImportedRig(std::move(cameras), options, source);
  return result;
}

RigImport importCalibration(const fs::path& path, const RigImportOptions& options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    if (fs::exists(path / "intri.yml") && fs::exists(path / "extri.yml"))
      return importEasyMocapRig(path, options);
    for (const fs::directory_entry& entry : fs::directory_iterator(path, ec))
      if (entry.path().filename().string().ends_with(".Pmat.cal"))
        return importSvobodaRig(path, options);
    throw Error(path.string() +
                ": a folder of no calibration Lumistage reads (EasyMocap's intri.yml and "
                "extri.yml, or MultiCamSelfCal's *.Pmat.cal)");
  }
  if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
  const std::string name = path.filename().string();
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (name.ends_with(".qca.txt")) return importQualisysRig(path, options);
  if (extension == ".toml") return importTomlRig(path, options);
  if (extension == ".yaml" || extension == ".yml" || extension == ".xml" || extension == ".json") {
    // A rig file says so in its first lines (rig_file.h writes them); anything else of these
    // endings is taken for OpenCV's.
    std::ifstream in(path);
    std::string line;
    for (int i = 0; i < 16 && std::getline(in, line); ++i)
      if (line.starts_with("format: lumistage-rig")) return {loadRig(path), {}};
    return importOpenCvRig(path, options);
  }
  throw Error(path.string() +
              ": not a calibration Lumistage reads (a rig file .yaml, Qualisys .qca.txt, "
              "Pose2Sim/anipose .toml, OpenCV .yaml/.yml/.xml/.json, or an EasyMocap or "
              "MultiCamSelfCal folder)");
}

}  // namespace lumistage
