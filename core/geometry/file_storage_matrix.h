#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace lumistage {

// The most numbers a matrix in a calibration file may declare: K is 9, OpenCV's longest
// distortion model 14. OpenCV allocates an !!opencv-matrix's declared rows x cols before it counts
// its data, so `rows: 2000000000` asked for gigabytes; the declaration is checked first.
inline constexpr int kMaxFileStorageMatrixNumbers = 4096;

// A matrix from an OpenCV FileStorage node: an !!opencv-matrix (its declared size checked against
// kMaxFileStorageMatrixNumbers before OpenCV reads it) or a sequence of numbers (one row). Returns
// it single-channel CV_64F, empty where the node holds nothing readable. Throws Error "where:
// expected a matrix: ..." for anything OpenCV refuses or throws (cv::Exception or other).
cv::Mat readFileStorageMatrix(const cv::FileNode& node, const std::string& where);

}  // namespace lumistage
