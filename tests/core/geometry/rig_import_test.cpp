// The rig importers of calibration toolboxes' files: MultiCamSelfCal's (Svoboda) and OpenCV's
// FileStorage, against cameras whose truth is known, bad files and fuzzed ones.
#include "core/geometry/rig_import.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <random>

#include "core/base/error.h"
#include "core/geometry/ring_rig.h"
#include "tests/core/geometry/temp_folder.h"
#include "tests/core/geometry/test_cameras.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;

// What MultiCamSelfCal writes: P scaled arbitrarily, one row a line.
std::string pmatText(const Eigen::Matrix<double, 3, 4>& P) {
  std::ostringstream out;
  out.precision(17);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) out << P(r, c) << (c < 3 ? " " : "\n");
  }
  return out.str();
}

std::string radText(const Eigen::Matrix3d& K, const Distortion& d) {
  std::ostringstream out;
  out.precision(17);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out << "K" << r + 1 << c + 1 << " = " << K(r, c) << "\n";
  }
  out << "\nkc1 = " << d.k1 << "\nkc2 = " << d.k2 << "\nkc3 = " << d.p1 << "\nkc4 = " << d.p2
      << "\n";
  return out.str();
}

// Cameras of one size (Svoboda's output has one size for all).
std::vector<Camera> cameraSet(std::mt19937& rng, int count, bool distorted) {
  std::vector<Camera> cameras;
  while (static_cast<int>(cameras.size()) < count) {
    Camera c = testing::randomCamera(rng, distorted);
    if (c.width() == 1024)
      cameras.push_back(c);
    else {
      cameras.emplace_back("cam", 1024, 768, c.intrinsics(), c.distortion(), c.rotation(),
                           c.translation());
    }
  }
  return cameras;
}

TEST(SvobodaImport, RecoversEveryCameraFromProjectionAndRadFiles) {
  std::mt19937 rng(21);
  const std::vector<Camera> truth = cameraSet(rng, 11, true);
  TempFolder folder;
  for (size_t i = 0; i < truth.size(); ++i) {
    Distortion d = truth[i].distortion();
    d.k3 = 0;  // .rad files of the toolbox carry kc1..kc4
    const double scale = (i % 2 ? -1.0 : 1.0) * (0.001 + i);
    // Half of them as the toolbox writes them under Octave: with its header of comments.
    const std::string octave =
        i % 2 ? "# Created by Octave 8.4.0, Tue Nov 25 10:12:33 2025 CET <user@stage>\n"
                "# name: Pmat\n# type: matrix\n# rows: 3\n# columns: 4\n"
              : "";
    folder.write("camera" + std::to_string(i + 1) + ".Pmat.cal",
                 octave + pmatText(scale * truth[i].projectionMatrix()));
    folder.write("cam" + std::to_string(i + 1) + ".rad",
                 radText(truth[i].intrinsics().matrix(), d));
  }
  RigImportOptions options;
  options.width = 1024;
  options.height = 768;
  const RigImport imported = importSvobodaRig(folder.path(), options);
  ASSERT_EQ(imported.rig.cameraCount(), 11);
  EXPECT_EQ(imported.rig.nodeCount(), 4);  // ceil(11 / 3)
  EXPECT_TRUE(imported.notes.empty());
  for (int i = 0; i < 11; ++i) {
    const Camera& c = imported.rig.camera(i);
    EXPECT_EQ(c.name(), "camera" + std::to_string(i + 1));  // natural order: camera10 after camera9
    EXPECT_LT((c.intrinsics().matrix() - truth[i].intrinsics().matrix()).norm(), 1e-6);
    EXPECT_LT((c.rotation() - truth[i].rotation()).norm(), 1e-9);
    EXPECT_LT((c.centre() - truth[i].centre()).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(c.distortion().k1, truth[i].distortion().k1);
    EXPECT_DOUBLE_EQ(c.distortion().p2, truth[i].distortion().p2);
  }
}

TEST(SvobodaImport, RefitsDistortionWhenTheRadHasAnotherK) {
  std::mt19937 rng(22);
  const Camera truth = cameraSet(rng, 1, false)[0];
  // The .rad's K (from an earlier intrinsic calibration) differs a little from the self-calibrated
  // P's K; the true pixel is K_rad · D(K_rad⁻¹ · P X).
  Eigen::Matrix3d K_rad = truth.intrinsics().matrix();
  K_rad(0, 0) *= 1.02;
  K_rad(1, 1) *= 1.02;
  K_rad(0, 2) += 6;
  const Distortion d_rad{-0.12, 0.03, 0.0005, -0.0004, 0};
  TempFolder folder;
  folder.write("camera1.Pmat.cal", pmatText(truth.projectionMatrix()));
  folder.write("camera1.rad", radText(K_rad, d_rad));
  RigImportOptions options;
  options.width = 1024;
  options.height = 768;
  const RigImport imported = importSvobodaRig(folder.path(), options);
  ASSERT_EQ(imported.notes.size(), 1u);
  EXPECT_NE(imported.notes[0].find("refitted"), std::string::npos);
  const Camera& c = imported.rig.camera(0);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  double worst = 0;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d X(u(rng), u(rng), 1 + u(rng));
    const Eigen::Vector3d ideal = truth.projectionMatrix() * X.homogeneous();
    const Eigen::Vector3d x_rad = K_rad.inverse() * ideal;
    const Eigen::Vector2d xd = d_rad.apply(x_rad.hnormalized());
    const Eigen::Vector2d expected = (K_rad * xd.homogeneous()).hnormalized();
    const std::optional<Eigen::Vector2d> got = c.project(X);
    ASSERT_TRUE(got);
    if (c.inImage(*got)) worst = std::max(worst, (*got - expected).norm());
  }
  EXPECT_LT(worst, 0.05);  // pixels
}

TEST(SvobodaImport, BadFoldersAndFilesAreNamed) {
  RigImportOptions options;
  options.width = 1024;
  options.height = 768;
  TempFolder empty;
  EXPECT_NE(testing::errorOf([&] {
              importSvobodaRig(empty.path(), options);
            }).find("no *.Pmat.cal files"),
            std::string::npos);
  EXPECT_NE(testing::errorOf([&] {
              importSvobodaRig(empty.path() / "missing", options);
            }).find("no such folder"),
            std::string::npos);

  TempFolder short_p;
  short_p.write("camera1.Pmat.cal", "1 0 0 0\n0 1 0 0\n");
  const std::string e = testing::errorOf([&] { importSvobodaRig(short_p.path(), options); });
  EXPECT_NE(
      e.find(
          "camera1.Pmat.cal: expected 12 numbers (a 3x4 projection matrix, row by row), found 8"),
      std::string::npos)
      << e;

  TempFolder bad_number;
  bad_number.write("camera1.Pmat.cal", "1 0 0 0\n0 1 x0 0\n0 0 1 1\n");
  EXPECT_NE(testing::errorOf([&] {
              importSvobodaRig(bad_number.path(), options);
            }).find("camera1.Pmat.cal:2: expected a number, got 'x0'"),
            std::string::npos);

  TempFolder singular;
  singular.write("camera1.Pmat.cal", "1 0 0 0\n2 0 0 0\n0 0 1 1\n");
  EXPECT_NE(testing::errorOf([&] { importSvobodaRig(singular.path(), options); }).find("singular"),
            std::string::npos);

  TempFolder bad_rad;
  bad_rad.write("camera1.Pmat.cal", "800 0 512 0\n0 800 384 0\n0 0 1 3\n");
  bad_rad.write("camera1.rad", "K11 = 800\nK12 = 0\n");
  EXPECT_NE(testing::errorOf([&] {
              importSvobodaRig(bad_rad.path(), options);
            }).find("camera1.rad: missing key 'K13'"),
            std::string::npos);

  RigImportOptions no_size;
  EXPECT_NE(
      testing::errorOf([&] { importSvobodaRig(bad_rad.path(), no_size); }).find("no image size"),
      std::string::npos);
}

TEST(OpenCvImport, ReadsFileStorageCamerasWithRotationMatrixOrRodrigues) {
  std::mt19937 rng(23);
  std::vector<Camera> truth;
  for (int i = 0; i < 4; ++i)
    truth.push_back(testing::randomCamera(rng, true, false, "cv" + std::to_string(i)));
  TempFolder folder;
  const std::string file = (folder.path() / "calib.yaml").string();
  {
    cv::FileStorage fs(file, cv::FileStorage::WRITE);
    fs << "cameras"
       << "[";
    for (size_t i = 0; i < truth.size(); ++i) {
      const Camera& c = truth[i];
      cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F), R(3, 3, CV_64F), T(3, 1, CV_64F);
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
          K.at<double>(r, k) = c.intrinsics().matrix()(r, k);
          R.at<double>(r, k) = c.rotation()(r, k);
        }
        T.at<double>(r) = c.translation()(r);
      }
      const Distortion& d = c.distortion();
      D.at<double>(0) = d.k1, D.at<double>(1) = d.k2, D.at<double>(2) = d.p1;
      D.at<double>(3) = d.p2, D.at<double>(4) = d.k3;
      fs << "{"
         << "name" << c.name() << "image_width" << c.width() << "image_height" << c.height()
         << "camera_matrix" << K << "distortion_coefficients" << D;
      if (i % 2 == 0) {
        fs << "R" << R;
      } else {
        const Eigen::AngleAxisd aa(c.rotation());
        cv::Mat rvec(3, 1, CV_64F);
        for (int r = 0; r < 3; ++r) rvec.at<double>(r) = aa.angle() * aa.axis()(r);
        fs << "rvec" << rvec;
      }
      fs << "T" << T << "}";
    }
    fs << "]";
  }
  RigImportOptions options;
  options.cameras_per_node = 2;
  const RigImport imported = importOpenCvRig(file, options);
  ASSERT_EQ(imported.rig.cameraCount(), 4);
  EXPECT_EQ(imported.rig.nodeCount(), 2);
  for (int i = 0; i < 4; ++i) {
    const Camera& c = imported.rig.camera(i);
    EXPECT_EQ(c.name(), truth[i].name());
    EXPECT_EQ(c.width(), truth[i].width());
    EXPECT_LT((c.intrinsics().matrix() - truth[i].intrinsics().matrix()).norm(), 1e-9);
    EXPECT_LT((c.rotation() - truth[i].rotation()).norm(), 1e-9);
    EXPECT_LT((c.translation() - truth[i].translation()).norm(), 1e-12);
    EXPECT_TRUE(c.distortion() == truth[i].distortion());
  }
}

TEST(OpenCvImport, MissingKeysAndUnsupportedModelsAreNamed) {
  TempFolder folder;
  folder.write("no_k.yaml", "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n");
  const std::string e = testing::errorOf([&] { importOpenCvRig(folder.path() / "no_k.yaml", {}); });
  EXPECT_NE(e.find("no_k.yaml: camera 0 ('cam01'): missing key 'camera_matrix'"), std::string::npos)
      << e;

  folder.write("rational.yaml",
               "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
               "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
               "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n"
               "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 8\n  dt: d\n"
               "  data: [0.1, 0, 0, 0, 0, 0.3, 0, 0]\n");
  const std::string r =
      testing::errorOf([&] { importOpenCvRig(folder.path() / "rational.yaml", {}); });
  EXPECT_NE(r.find("coefficient 6 is 0.3; only k1 k2 p1 p2 k3 are supported"), std::string::npos)
      << r;

  folder.write("garbage.yaml", "%YAML:1.0\n---\ncamera_matrix: [1, 2\n");
  EXPECT_NE(testing::errorOf([&] {
              importOpenCvRig(folder.path() / "garbage.yaml", {});
            }).find("garbage.yaml"),
            std::string::npos);
}

// OpenCV's FileStorage parsers recurse per level of nesting: 100,000 levels ended the process
// with SIGSEGV. Each way the formats nest is refused with file:line before OpenCV reads it.
TEST(OpenCvImport, DeeplyNestedFilesAreRefusedBeforeOpenCvParsesThem) {
  TempFolder folder;
  constexpr int kDepth = 100000;
  const std::string head = "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  std::string block = head;
  for (int i = 0; i < 2000; ++i) block += std::string(size_t(i), ' ') + "a:\n";
  std::string items = head + "k:\n";
  for (int i = 0; i < kDepth; ++i) items += "- ";
  items += "1\n";
  std::string xml = "<?xml version=\"1.0\"?>\n<opencv_storage>\n<!-- a comment -->\n";
  for (int i = 0; i < kDepth; ++i) xml += "<a>";
  const std::map<std::string, std::string> files = {
      {"flow.yaml", head + "k: " + std::string(kDepth, '[') + "1" + std::string(kDepth, ']')},
      {"maps.yaml", head + "k: " + std::string(kDepth, '{') + "a: 1" + std::string(kDepth, '}')},
      {"block.yaml", block},
      {"items.yaml", items},
      {"deep.xml", xml},
      {"deep.json", "{\"k\": " + std::string(kDepth, '[') + "1" + std::string(kDepth, ']') + "}"},
      // Closing brackets in quotes do not close.
      {"quoted.yaml", head + "k: " + [] {
         std::string t;
         for (int i = 0; i < kDepth; ++i) t += "[ ']' ";
         return t;
       }()}};
  for (const auto& [name, text] : files) {
    folder.write(name, text);
    const std::string e = testing::errorOf([&] { importOpenCvRig(folder.path() / name, {}); });
    EXPECT_NE(e.find(name + ":"), std::string::npos) << name << ": " << e.substr(0, 300);
    EXPECT_NE(e.find("nested deeper than 64 levels"), std::string::npos)
        << name << ": " << e.substr(0, 300);
  }
  // Nesting a calibration's few levels, XML's self-closing elements and brackets in comments
  // and strings still reach OpenCV.
  folder.write(
      "fine.xml",
      "<?xml version=\"1.0\"?>\n<opencv_storage>\n<!-- <a><a><a> -->\n" + std::string(200, ' ') +
          "<image_width>640</image_width><image_height>480</image_height>\n"
          "<camera_matrix type_id=\"opencv-matrix\"><rows>3</rows>"
          "<cols>3</cols><dt>d</dt><data>500 0 320 0 500 240 0 0 1</data>"
          "</camera_matrix>\n<distortion_coefficients type_id=\"opencv-matrix\"><rows>1</rows>"
          "<cols>5</cols><dt>d</dt><data>0 0 0 0 0</data></distortion_coefficients>\n"
          "</opencv_storage>\n");
  // Read by OpenCV to the end: it is the missing pose that is said.
  EXPECT_NE(testing::errorOf([&] {
              importOpenCvRig(folder.path() / "fine.xml", {});
            }).find("missing key 'rvec'"),
            std::string::npos);
  std::string flat = "<?xml version=\"1.0\"?>\n<opencv_storage>\n";
  for (int i = 0; i < 1000; ++i) flat += "<b a=\"/>\"/>";
  folder.write("flat.xml", flat + "\n</opencv_storage>\n");
  const std::string f = testing::errorOf([&] { importOpenCvRig(folder.path() / "flat.xml", {}); });
  EXPECT_EQ(f.find("nested deeper"), std::string::npos) << f.substr(0, 300);
  folder.write("fine.yaml", head + "# " + std::string(100, '[') + "\nnote: \"]]]] {[\"\n" +
                                "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
                                "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n"
                                "distortion_coefficients: [0, 0, 0, 0, 0]\n");
  // Read by OpenCV to the end: it is the missing pose that is said.
  EXPECT_NE(testing::errorOf([&] {
              importOpenCvRig(folder.path() / "fine.yaml", {});
            }).find("missing key 'rvec'"),
            std::string::npos);
}

// Found by the file_reader_fuzz_opencv target: each was a crash, a hang, gigabytes asked for or an
// exception that was not our Error, before OpenCV or inside it. Each is refused naming the file.
TEST(OpenCvImport, FuzzedFilesAreRefusedNamingTheFile) {
  TempFolder folder;
  const std::string head = "%YAML:1.0\n---\n";
  const std::string k =
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
      "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\ndistortion_coefficients: [0, 0, 0, 0]\n";
  const std::map<std::string, std::pair<std::string, std::string>> files = {
      // OpenCV allocated the declared rows x cols (48 GB here) before counting the data.
      {"huge.yaml",
       {head + "camera_matrix: !!opencv-matrix\n  rows: 2000000000\n  cols: 3\n  dt: d\n"
               "  data: [1]\n",
        "huge.yaml: camera 0 ('cam01'): camera_matrix: expected a matrix of at most 4096 numbers"}},
      // OpenCV's XML parser dereferenced a null pointer.
      {"nul.xml",
       {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<a>" + std::string(2, '\0') +
            "</a>\n</opencv_storage>\n",
        "nul.xml:3: a NUL byte"}},
      // ... and on a declaration cut short.
      {"declaration.xml",
       {"<?xml version=", "declaration.xml:1: an XML declaration that does not"}},
      {"root.xml",
       {"<?xml version=\"1.0\"?>\n<a>1</a>\n", "root.xml: XML without OpenCV's root element"}},
      // OpenCV's YAML parser looped forever.
      {"start.yaml", {"%YAML:1.0\n--- t: 0\n--x-\n", "start.yaml:2: content on the document's"}},
      {"indented.yaml",
       {"%YAML:1.\n -a\n---\n#\n -", "indented.yaml:2: the document's first key not at column 0"}},
      {"end.yaml", {head + "t: 0\n...\n--x\n", "end.yaml:5: text after the document's end"}},
      {"dash.yaml", {head + "t: 0\n--x\n", "dash.yaml:4: a line at column 0 starting with '-'"}},
      // OpenCV's YAML parser threw std::length_error, which is no cv::Exception.
      {"key.yaml",
       {head + "K: !!opencv-matrix\n   rows: 3\n   : 3\n",
        "key.yaml: not a valid OpenCV FileStorage file"}},
      // A double past int's range was converted to int.
      {"size.yaml",
       {head + "image_size: [1e300, 720]\n" + k,
        "size.yaml: camera 0 ('cam01'): image_size: expected whole numbers of pixels"}},
      // A name from the file is shown quoted.
      {"name.yaml",
       {head + "name: \"cam 1/../x\"\n" + k, "name.yaml: camera 0: name 'cam 1/../x' is not"}}};
  for (const auto& [name, file] : files) {
    folder.write(name, file.first);
    const std::string e = testing::errorOf([&] { importOpenCvRig(folder.path() / name, {}); });
    EXPECT_NE(e.find(file.second), std::string::npos) << name << ": " << e;
  }
  // A calibration as a person writes it by hand still reads: "---" alone, "..." at the end.
  folder.write("hand.yaml", head + "# by hand\nimage_width: 640\nimage_height: 480\n" + k +
                                "rvec: [0, 0, 0]\ntvec: [0, 0, 2]\n...\n# the end\n");
  EXPECT_EQ(importOpenCvRig(folder.path() / "hand.yaml", {}).rig.cameraCount(), 1);
}

}  // namespace
}  // namespace lumistage
