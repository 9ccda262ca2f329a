// EasyMocap's calibrations: intri.yml and extri.yml, OpenCV FileStorage files.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/names.h"
#include "core/geometry/file_storage_matrix.h"
#include "core/geometry/file_storage_nesting.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/rotation.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// Matrix `key` of `file` with `count` numbers (any shape). Throws Error naming both.
std::vector<double> numbersOf(const cv::FileStorage& storage, const std::string& key,
                              const std::vector<size_t>& counts, const fs::path& file) {
  const cv::FileNode node = storage[key];
  if (node.empty()) throw Error(fmt::format("{}: no '{}'", file.string(), key));
  const cv::Mat m = readFileStorageMatrix(node, file.string() + ": " + key);
  std::vector<double> values;
  if (!m.empty()) values.assign(m.begin<double>(), m.end<double>());
  bool counted = false;
  for (size_t n : counts) counted = counted || values.size() == n;
  if (!counted)
    throw Error(fmt::format("{}: {}: {} numbers, expected {}", file.string(), key, values.size(),
                            counts.front()));
  for (double v : values)
    if (!std::isfinite(v))
      throw Error(fmt::format("{}: {}: a number that is not finite", file.string(), key));
  return values;
}

// Image size `key` of `file`: a whole number of pixels (a double of one read as such), at most
// kMaxPixels. Throws Error naming both.
int pixels(const cv::FileStorage& storage, const std::string& key, const fs::path& file) {
  constexpr double kMaxPixels = 1 << 20;
  const cv::FileNode node = storage[key];
  const double value = node.isInt() || node.isReal() ? double(node) : 0.0;
  if (!(value >= 1 && value <= kMaxPixels) || value != std::floor(value))
    throw Error(fmt::format("{}: {}: expected a whole number of pixels from 1 to {}", file.string(),
                            key, kMaxPixels));
  return static_cast<int>(value);
}

cv::FileStorage open(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw Error(file.string() + ": no such file");
  checkFileStorageText(readFile(file), file.string());  // what OpenCV chokes on
  try {
    cv::FileStorage storage(file.string(), cv::FileStorage::READ);
    if (!storage.isOpened())
      throw Error(file.string() + ": cannot read as an OpenCV FileStorage file");
    return storage;
  } catch (const cv::Exception& e) {
    throw Error(file.string() + ": " + e.err);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    // OpenCV's parsers let other exceptions through too (std::length_error on a YAML key ": 3").
    throw Error(file.string() + ": cannot read as an OpenCV FileStorage file: " + e.what());
  }
}

std::vector<std::string> namesOf(const cv::FileStorage& storage, const fs::path& file) {
  const cv::FileNode node = storage["names"];
  if (node.empty() || !node.isSeq()) throw Error(file.string() + ": no 'names' list");
  std::vector<std::string> names;
  for (const cv::FileNode& n : node) {
    // EasyMocap writes camera names as strings; some tools write numbers.
    const std::string name = n.isString() ? std::string(n)
                             : n.isInt()  ? std::to_string(int(n))
                                          : std::string();
    if (!isValidName(name))
      throw Error(fmt::format("{}: names: {} is not a camera name (1-64 of A-Za-z0-9_.-)",
                              file.string(), n.isString() ? quotedInput(name) : "an entry"));
    names.push_back(name);
  }
  return names;
}

}  // namespace

RigImport importEasyMocapRig(const fs::path& folder, const RigImportOptions& options) {
  const fs::path intri_file = folder / "intri.yml", extri_file = folder / "extri.yml";
  const cv::FileStorage intri = open(intri_file), extri = open(extri_file);
  const std::vector<std::string> names = namesOf(intri, intri_file);
  RigImport result;
  std::vector<Camera> cameras;
  for (const std::string& name : names) {
    const std::vector<double> k = numbersOf(intri, "K_" + name, {9}, intri_file);
    const std::vector<double> d = numbersOf(intri, "dist_" + name, {5, 4}, intri_file);
    // Rot_ is the rotation matrix, R_ its Rodrigues vector: either will do, Rot_ first.
    Eigen::Matrix3d R;
    if (!extri["Rot_" + name].empty()) {
      const std::vector<double> r = numbersOf(extri, "Rot_" + name, {9}, extri_file);
      for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = r[size_t(i)];
    } else {
      const std::vector<double> r = numbersOf(extri, "R_" + name, {3}, extri_file);
      R = rotationFromVector({r[0], r[1], r[2]});
    }
    if ((R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-4)
      throw Error(fmt::format("{}: Rot_{}: not a rotation", extri_file.string(), name));
    const std::vector<double> t = numbersOf(extri, "T_" + name, {3}, extri_file);
    // The image size: EasyMocap leaves it out; H_ and W_ where a tool adds them, else the option.
    int width = options.width, height = options.height;
    if (!intri["W_" + name].empty() && !intri["H_" + name].empty()) {
      width = pixels(intri, "W_" + name, intri_file);
      height = pixels(intri, "H_" + name, intri_file);
    }
    if (width <= 0 || height <= 0)
      throw Error(fmt::format("{}: camera '{}' has no image size: give it (--image-size WxH)",
                              intri_file.string(), name));
    Eigen::Matrix3d K;
    for (int i = 0; i < 9; ++i) K(i / 3, i % 3) = k[size_t(i)];
    if (!(K(0, 0) > 0 && K(1, 1) > 0) || K(2, 2) == 0)
      throw Error(
          fmt::format("{}: K_{}: expected positive focal lengths", intri_file.string(), name));
    const Distortion distortion{d[0], d[1], d[2], d[3], d.size() > 4 ? d[4] : 0.0};
    try {
      cameras.emplace_back(name, width, height, Intrinsics::fromMatrix(K), distortion, R,
                           Eigen::Vector3d(t[0], t[1], t[2]));
    } catch (const std::invalid_argument& e) {
      throw Error(intri_file.string() + ": " + e.what());
    }
  }
  result.rig = assembleImportedRig(std::move(cameras), options, folder.string());
  return result;
}

}  // namespace lumistage
