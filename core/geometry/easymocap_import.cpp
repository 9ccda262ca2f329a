// EasyMocap's calibrations: intri.yml and extri.yml, OpenCV FileStorage files.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/core.hpp>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
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
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception& e) {
    throw Error(fmt::format("{}: {}: expected a matrix: {}", file.string(), key, e.err));
  }
  m.convertTo(m, CV_64F);
  std::vector<double> values(m.begin<double>(), m.end<double>());
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

cv::FileStorage open(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw Error(file.string() + ": no such file");
  checkFileStorageNesting(readFile(file), file.string());  // OpenCV's parsers recurse per level
  try {
    cv::FileStorage storage(file.string(), cv::FileStorage::READ);
    if (!storage.isOpened())
      throw Error(file.string() + ": cannot read as an OpenCV FileStorage file");
    return storage;
  } catch (const cv::Exception& e) {
    throw Error(file.string() + ": " + e.err);
  }
}

std::vector<std::string> namesOf(const cv::FileStorage& storage, const fs::path& file) {
  const cv::FileNode node = storage["names"];
  if (node.empty() || !node.isSeq()) throw Error(file.string() + ": no 'names' list");
  std::vector<std::string> names;
  for (const cv::FileNode& n : node) {
    // EasyMocap writes camera names as strings; some tools write numbers.
    names.push_back(n.isString() ? std::string(n) : fmt::format("{}", int(double(n))));
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
      width = int(double(intri["W_" + name]));
      height = int(double(intri["H_" + name]));
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
    cameras.emplace_back(name, width, height, Intrinsics::fromMatrix(K), distortion, R,
                         Eigen::Vector3d(t[0], t[1], t[2]));
  }
  result.rig = assembleImportedRig(std::move(cameras), options, folder.string());
  return result;
}

}  // namespace lumistage
