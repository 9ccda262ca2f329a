#include "core/geometry/file_storage_matrix.h"

#include <fmt/format.h>

#include <cstdint>
#include <exception>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

// An !!opencv-matrix's declared size, refused when it is not a few positive whole numbers or
// declares more than kMaxFileStorageMatrixNumbers (before OpenCV allocates it).
void checkDeclaredSize(const cv::FileNode& node, const std::string& where) {
  std::vector<cv::FileNode> extents;
  if (const cv::FileNode sizes = node["sizes"]; !sizes.empty()) {
    if (!sizes.isSeq() || sizes.size() == 0 || sizes.size() > 4)
      throw Error(where + ": expected a matrix: 'sizes' is not a list of 1 to 4 numbers");
    for (const cv::FileNode& extent : sizes) extents.push_back(extent);
  } else {
    extents = {node["rows"], node["cols"]};
  }
  int64_t numbers = 1;
  for (const cv::FileNode& extent : extents) {
    if (!extent.isInt())
      throw Error(where + ": expected a matrix: its rows, cols or sizes are not whole numbers");
    const int64_t n = static_cast<int>(extent);
    if (n < 0 || n > kMaxFileStorageMatrixNumbers || (numbers *= n) > kMaxFileStorageMatrixNumbers)
      throw Error(
          fmt::format("{}: expected a matrix of at most {} numbers: its declared size is "
                      "out of range",
                      where, kMaxFileStorageMatrixNumbers));
  }
}

}  // namespace

cv::Mat readFileStorageMatrix(const cv::FileNode& node, const std::string& where) {
  cv::Mat m;
  try {
    if (node.isSeq()) {
      std::vector<double> values;
      node >> values;
      m = cv::Mat(values, true).reshape(1, 1);
    } else {
      if (node.isMap()) checkDeclaredSize(node, where);
      node >> m;
    }
    if (m.empty()) return {};
    // Channels ("dt: 3d") and dimensions past two ("sizes") as plain numbers.
    if (m.dims > 2)
      m = m.reshape(1, 1);
    else if (m.channels() > 1)
      m = m.reshape(1);
    m.convertTo(m, CV_64F);
  } catch (const Error&) {
    throw;
  } catch (const cv::Exception& e) {
    throw Error(where + ": expected a matrix: " + e.err);
  } catch (const std::exception& e) {
    throw Error(where + ": expected a matrix: " + e.what());
  }
  return m;
}

}  // namespace lumistage
