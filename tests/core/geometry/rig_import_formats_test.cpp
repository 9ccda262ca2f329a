// The rig importers of the motion-capture tools' formats: Qualisys QTM, Pose2Sim/anipose TOML and
// EasyMocap, against cameras whose truth is known and against the real files they read.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <random>

#include "core/base/error.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/ring_rig.h"
#include "tests/core/geometry/temp_folder.h"
#include "tests/core/geometry/test_cameras.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;
std::vector<Camera> ringCameras(int count, int width, int height) {
  RingRigSpec spec;
  spec.cameras = count;
  spec.width = width;
  spec.height = height;
  spec.distortion = {-0.05, 0.02, 0.0004, -0.0003, 0.0};
  return makeRingRig(spec).cameras();
}

// A camera as QTM writes it: intrinsics and distortion in 1/64 pixel, the position in mm, the
// rotation turned half a turn about the camera's x from ours.
std::string qcaCamera(const Camera& c, const std::string& serial, int line_left = 0) {
  const Eigen::Matrix3d m = Eigen::Vector3d(1, -1, -1).asDiagonal() * c.rotation();
  const Eigen::Vector3d p = 1000 * c.centre();
  const Intrinsics& k = c.intrinsics();
  const Distortion& d = c.distortion();
  return fmt::format(
      "    <camera active=\"1\" avg-residual=\"0.4\" model=\"none\" serial=\"{}\" "
      "viewrotation=\"0\">\n"
      "      <fov_video bottom=\"{}\" left=\"{}\" right=\"{}\" top=\"0\"/>\n"
      "      <transform r11=\"{:.17g}\" r12=\"{:.17g}\" r13=\"{:.17g}\" r21=\"{:.17g}\" "
      "r22=\"{:.17g}\" r23=\"{:.17g}\" r31=\"{:.17g}\" r32=\"{:.17g}\" r33=\"{:.17g}\" "
      "x=\"{:.17g}\" y=\"{:.17g}\" z=\"{:.17g}\"/>\n"
      "      <intrinsic centerPointU=\"{:.17g}\" centerPointV=\"{:.17g}\" focalLengthU=\"{:.17g}\" "
      "focalLengthV=\"{:.17g}\" radialDistortion1=\"{:.17g}\" radialDistortion2=\"{:.17g}\" "
      "radialDistortion3=\"0\" skew=\"0\" tangentalDistortion1=\"{:.17g}\" "
      "tangentalDistortion2=\"{:.17g}\"/>\n"
      "    </camera>\n",
      serial, c.height() - 1, line_left, line_left + c.width() - 1, m(0, 0), m(0, 1), m(0, 2),
      m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2), p.x(), p.y(), p.z(),
      64 * (k.cx + line_left), 64 * k.cy, 64 * k.fx, 64 * k.fy, 64 * d.k1, 64 * d.k2, 64 * d.p1,
      64 * d.p2);
}

TEST(QualisysImport, RecoversEveryVideoCameraInNaturalOrder) {
  const std::vector<Camera> truth = ringCameras(3, 1088, 1920);
  TempFolder folder;
  std::string text =
      "<?xml version='1.0' encoding='ASCII'?>\n<calibration type=\"regular\">\n"
      "  <!-- three video cameras and a marker camera -->\n  <cameras>\n";
  text += qcaCamera(truth[2], "cam10", 16);
  text += qcaCamera(truth[0], "cam2");
  text +=
      "    <camera active=\"1\" serial=\"marker1\" model=\"Miqus M3\">\n"
      "      <fov_marker bottom=\"1023\" left=\"0\" right=\"1279\" top=\"0\"/>\n"
      "    </camera>\n";
  text += qcaCamera(truth[1], "cam3");
  text += "  </cameras>\n</calibration>\n";
  folder.write("Calib.qca.txt", text);
  const RigImport imported = importQualisysRig(folder.path() / "Calib.qca.txt", {});
  ASSERT_EQ(imported.rig.cameraCount(), 3);
  EXPECT_EQ(imported.rig.camera(0).name(), "cam2");
  EXPECT_EQ(imported.rig.camera(1).name(), "cam3");
  EXPECT_EQ(imported.rig.camera(2).name(), "cam10");
  ASSERT_EQ(imported.notes.size(), 1u);
  EXPECT_NE(imported.notes[0].find("marker1"), std::string::npos);
  const Camera* expected[] = {&truth[0], &truth[1], &truth[2]};
  for (int c = 0; c < 3; ++c) {
    const Camera& got = imported.rig.camera(c);
    EXPECT_EQ(got.width(), 1088);
    EXPECT_EQ(got.height(), 1920);
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.4, -0.3, 1.7),
                                     Eigen::Vector3d(-0.5, 0.2, 0.1)}) {
      const auto a = got.project(p), b = expected[c]->project(p);
      ASSERT_TRUE(a && b);
      EXPECT_LT((*a - *b).norm(), 1e-6) << got.name();
    }
  }
}

TEST(QualisysImport, MalformedFilesNameFileLineAndAttribute) {
  const std::vector<Camera> truth = ringCameras(1, 640, 480);
  TempFolder folder;
  const std::string good = "<calibration>\n  <cameras>\n" + qcaCamera(truth[0], "cam01") +
                           "  </cameras>\n</calibration>\n";
  const auto errorOf = [&](const std::string& text) {
    folder.write("c.qca.txt", text);
    return testing::errorOf([&] { importQualisysRig(folder.path() / "c.qca.txt", {}); });
  };
  std::string text = good;
  text.replace(text.find(" r23=\""), 6, " r99=\"");
  std::string e = errorOf(text);
  EXPECT_NE(e.find("c.qca.txt:5: camera 'cam01': r23: <transform> has no 'r23'"), std::string::npos)
      << e;
  text = good;
  text.replace(text.find("focalLengthU=\""), 14, "focalLengthU=\"abc");
  e = errorOf(text);
  EXPECT_NE(e.find("c.qca.txt:6: camera 'cam01': focalLengthU: expected a number, got 'abc"),
            std::string::npos)
      << e;
  e = errorOf(good.substr(0, good.find("</camera>")));
  EXPECT_NE(e.find("camera 'cam01' never ends"), std::string::npos) << e;
  e = errorOf("<calibration>\n  <cameras>\n  </cameras>\n</calibration>\n");
  EXPECT_NE(e.find("no video camera"), std::string::npos) << e;
  text = good;
  text.replace(text.find("r11=\""), 5, "r11=\"2");
  e = errorOf(text);
  EXPECT_NE(e.find("r11..r33 are not a rotation"), std::string::npos) << e;
}

// The Pose2Sim demo's calibration: four portrait cameras around the treadmill, about 1.9 m high,
// each seeing the origin.
TEST(QualisysImport, ReadsThePose2SimDemosCalibration) {
  const fs::path file = testing::realData() / "pose2sim-walk" / "calibration" / "Calib.qca.txt";
  if (!fs::exists(file)) GTEST_SKIP() << file << " is not here";
  const RigImport imported = importQualisysRig(file, {});
  ASSERT_EQ(imported.rig.cameraCount(), 4);
  for (int c = 0; c < 4; ++c) {
    const Camera& camera = imported.rig.camera(c);
    EXPECT_EQ(camera.name(), fmt::format("cam{:02}", c + 1));
    EXPECT_EQ(camera.width(), 1088);
    EXPECT_EQ(camera.height(), 1920);
    EXPECT_NEAR(camera.intrinsics().fx, 1680, 20);
    EXPECT_GT(camera.centre().z(), 1.5);
    EXPECT_LT(camera.centre().z(), 2.3);
    const auto origin = camera.project(Eigen::Vector3d(0, 0, 0.9));
    ASSERT_TRUE(origin.has_value()) << camera.name();
    EXPECT_GT(origin->x(), 0);
    EXPECT_LT(origin->x(), 1088);
    EXPECT_GT(origin->y(), 0);
    EXPECT_LT(origin->y(), 1920);
  }
}

// A camera as Pose2Sim's toml_write writes it (trailing commas, floats everywhere).
std::string tomlCamera(const Camera& c, const std::string& section) {
  const Eigen::AngleAxisd aa(c.rotation());
  const Eigen::Vector3d r = aa.angle() * aa.axis();
  const Intrinsics& k = c.intrinsics();
  const Distortion& d = c.distortion();
  return fmt::format(
      "[{}]\nname = \"{}\"\nsize = [ {}.0, {}.0,]\n"
      "matrix = [ [ {:.17g}, 0.0, {:.17g},], [ 0.0, {:.17g}, {:.17g},], [ 0.0, 0.0, 1.0,],]\n"
      "distortions = [ {:.17g}, {:.17g}, {:.17g}, {:.17g},]\n"
      "rotation = [ {:.17g}, {:.17g}, {:.17g},]\ntranslation = [ {:.17g}, {:.17g}, {:.17g},]\n"
      "fisheye = false\n\n",
      section, c.name(), c.width(), c.height(), k.fx, k.cx, k.fy, k.cy, d.k1, d.k2, d.p1, d.p2,
      r.x(), r.y(), r.z(), c.translation().x(), c.translation().y(), c.translation().z());
}

TEST(TomlImport, ReadsPose2SimCalibrationsInTheirTablesNaturalOrder) {
  const std::vector<Camera> truth = ringCameras(11, 1280, 720);
  TempFolder folder;
  std::string text = "# Pose2Sim calibration\n";
  for (int i = 10; i >= 0; --i) text += tomlCamera(truth[size_t(i)], fmt::format("cam_{}", i + 1));
  text += "[metadata]\nadjusted = false\nerror = 0.0\n";
  folder.write("Calib.toml", text);
  const RigImport imported = importTomlRig(folder.path() / "Calib.toml", {});
  ASSERT_EQ(imported.rig.cameraCount(), 11);
  for (int c = 0; c < 11; ++c) {
    const Camera& got = imported.rig.camera(c);
    EXPECT_EQ(got.name(), truth[size_t(c)].name());
    EXPECT_EQ(got.width(), 1280);
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.4, -0.3, 1.7)}) {
      const auto a = got.project(p), b = truth[size_t(c)].project(p);
      ASSERT_TRUE(a && b);
      EXPECT_LT((*a - *b).norm(), 1e-6) << got.name();
    }
  }
}

// toml11 recurses per level of nested arrays and inline tables: 100,000 levels overflowed the
// stack. Brackets in strings and comments are not nesting.
TEST(TomlImport, DeepNestingIsRefusedBeforeToml11ReadsIt) {
  const std::vector<Camera> truth = ringCameras(1, 640, 480);
  TempFolder folder;
  const std::string good = tomlCamera(truth[0], "cam_1");
  folder.write("deep.toml",
               good + "[extra]\nx = " + std::string(100000, '[') + std::string(100000, ']') + "\n");
  const std::string e = testing::errorOf([&] { importTomlRig(folder.path() / "deep.toml", {}); });
  EXPECT_NE(e.find("deep.toml:"), std::string::npos) << e.substr(0, 300);
  EXPECT_NE(e.find("nested deeper than 64 levels"), std::string::npos) << e.substr(0, 300);
  const std::string brackets(200, '[');
  folder.write("fine.toml", "# " + brackets + "\n" + good + "[metadata]\nnote = \"" + brackets +
                                "\"\nmore = \'" + brackets + "\'\nlong = \"\"\"\n" + brackets +
                                "\n\"\"\"\n");
  EXPECT_EQ(importTomlRig(folder.path() / "fine.toml", {}).rig.cameraCount(), 1);
}

// toml11 read past its buffer on a quote, a lone UTF-8 lead byte and a quote (file_reader_fuzz,
// AddressSanitizer): text that is not UTF-8 is refused before toml11 reads it; UTF-8 is read.
TEST(TomlImport, TextThatIsNotUtf8IsRefusedBeforeToml11ReadsIt) {
  const std::vector<Camera> truth = ringCameras(1, 640, 480);
  TempFolder folder;
  const std::string good = tomlCamera(truth[0], "cam_1");
  folder.write("cut.toml", good + "\n'\xee'");
  const std::string e = testing::errorOf([&] { importTomlRig(folder.path() / "cut.toml", {}); });
  EXPECT_NE(e.find("cut.toml:"), std::string::npos) << e;
  EXPECT_NE(e.find("byte 0xee is not UTF-8 text"), std::string::npos) << e;
  folder.write("latin1.toml", "# caf\xe9\n" + good);
  EXPECT_NE(testing::errorOf([&] {
              importTomlRig(folder.path() / "latin1.toml", {});
            }).find("latin1.toml:1: byte 0xe9"),
            std::string::npos);
  folder.write("utf8.toml", "# K\xc3\xa4the's cameras\n" + good);
  EXPECT_EQ(importTomlRig(folder.path() / "utf8.toml", {}).rig.cameraCount(), 1);
}

TEST(TomlImport, MalformedFilesAreNamed) {
  const std::vector<Camera> truth = ringCameras(1, 640, 480);
  TempFolder folder;
  const auto errorOf = [&](const std::string& text) {
    folder.write("c.toml", text);
    return testing::errorOf([&] { importTomlRig(folder.path() / "c.toml", {}); });
  };
  const std::string good = tomlCamera(truth[0], "cam_1");
  std::string text = good;
  text.replace(text.find("rotation = [ "), 13, "rotation = [ \"x\", ");
  std::string e = errorOf(text);
  EXPECT_NE(e.find("c.toml: [cam_1]: rotation: expected numbers"), std::string::npos) << e;
  text = good;
  text.replace(text.find("translation"), 11, "tra");
  e = errorOf(text);
  EXPECT_NE(e.find("[cam_1]: no 'translation'"), std::string::npos) << e;
  text = good;
  text.replace(text.find("fisheye = false"), 15, "fisheye = true");
  e = errorOf(text);
  EXPECT_NE(e.find("fisheye lens model is not supported"), std::string::npos) << e;
  e = errorOf(good.substr(0, good.find("matrix") + 14));
  EXPECT_NE(e.find("c.toml:5: missing array separator"), std::string::npos) << e;
  e = errorOf("[metadata]\nadjusted = false\n");
  EXPECT_NE(e.find("no camera tables"), std::string::npos) << e;
}

// intri.yml and extri.yml as EasyMocap's write_intri and write_extri write them.
void writeEasyMocap(const fs::path& folder, const std::vector<Camera>& cameras,
                    bool rotation_matrix, bool translation = true) {
  cv::FileStorage intri((folder / "intri.yml").string(), cv::FileStorage::WRITE);
  cv::FileStorage extri((folder / "extri.yml").string(), cv::FileStorage::WRITE);
  for (cv::FileStorage* f : {&intri, &extri}) {
    *f << "names"
       << "[";
    for (const Camera& c : cameras) *f << c.name();
    *f << "]";
  }
  for (const Camera& c : cameras) {
    cv::Mat K(3, 3, CV_64F), dist(1, 5, CV_64F), R(3, 3, CV_64F), rvec(3, 1, CV_64F),
        T(3, 1, CV_64F);
    const Eigen::Matrix3d k = c.intrinsics().matrix();
    const Eigen::AngleAxisd aa(c.rotation());
    const Eigen::Vector3d w = aa.angle() * aa.axis();
    for (int i = 0; i < 9; ++i) {
      K.at<double>(i / 3, i % 3) = k(i / 3, i % 3);
      R.at<double>(i / 3, i % 3) = c.rotation()(i / 3, i % 3);
    }
    const Distortion& d = c.distortion();
    const double coefficients[5] = {d.k1, d.k2, d.p1, d.p2, d.k3};
    for (int i = 0; i < 5; ++i) dist.at<double>(0, i) = coefficients[i];
    for (int i = 0; i < 3; ++i) rvec.at<double>(i) = w[i], T.at<double>(i) = c.translation()[i];
    intri << "K_" + c.name() << K << "dist_" + c.name() << dist;
    extri << "R_" + c.name() << rvec;
    if (rotation_matrix) extri << "Rot_" + c.name() << R;
    if (translation) extri << "T_" + c.name() << T;
  }
}

TEST(EasyMocapImport, ReadsIntriAndExtriInTheirNamesOrder) {
  const std::vector<Camera> truth = ringCameras(4, 1280, 720);
  RigImportOptions options;
  options.width = 1280;
  options.height = 720;
  for (const bool rotation_matrix : {true, false}) {
    TempFolder folder;
    writeEasyMocap(folder.path(), truth, rotation_matrix);
    const RigImport imported = importEasyMocapRig(folder.path(), options);
    ASSERT_EQ(imported.rig.cameraCount(), 4);
    for (int c = 0; c < 4; ++c) {
      const Camera& got = imported.rig.camera(c);
      EXPECT_EQ(got.name(), truth[size_t(c)].name());
      const auto a = got.project(Eigen::Vector3d(0.3, -0.2, 1.4)),
                 b = truth[size_t(c)].project(Eigen::Vector3d(0.3, -0.2, 1.4));
      ASSERT_TRUE(a && b);
      EXPECT_LT((*a - *b).norm(), 1e-6) << got.name();
    }
  }
}

TEST(EasyMocapImport, MissingPiecesAreNamed) {
  const std::vector<Camera> truth = ringCameras(2, 640, 480);
  TempFolder folder;
  writeEasyMocap(folder.path(), truth, true, /*translation=*/false);
  RigImportOptions options;
  std::string e = testing::errorOf([&] { importEasyMocapRig(folder.path(), options); });
  EXPECT_NE(e.find("extri.yml: no 'T_cam01'"), std::string::npos) << e;
  writeEasyMocap(folder.path(), truth, true);
  e = testing::errorOf([&] { importEasyMocapRig(folder.path(), options); });
  EXPECT_NE(e.find("camera 'cam01' has no image size: give it (--image-size WxH)"),
            std::string::npos)
      << e;
  e = testing::errorOf([&] { importEasyMocapRig(folder.path() / "nothing", options); });
  EXPECT_NE(e.find("intri.yml: no such file"), std::string::npos) << e;
}

TEST(EasyMocapImport, DeeplyNestedFilesAreRefusedBeforeOpenCvParsesThem) {
  const std::vector<Camera> truth = ringCameras(2, 640, 480);
  TempFolder folder;
  writeEasyMocap(folder.path(), truth, true);
  folder.write("extri.yml", "%YAML:1.0\nnames: " + std::string(100000, '[') + "\n");
  const std::string e = testing::errorOf([&] { importEasyMocapRig(folder.path(), {}); });
  EXPECT_NE(e.find("extri.yml:2: nested deeper than 64 levels"), std::string::npos)
      << e.substr(0, 300);
}

// Found by the file_reader_fuzz_easymocap target: an exception from OpenCV's parser that was not
// our Error, an unbounded matrix, and image sizes past int's range. Each is refused naming the
// file.
TEST(EasyMocapImport, FuzzedFilesAreRefusedNamingTheFile) {
  const std::vector<Camera> truth = ringCameras(2, 640, 480);
  TempFolder folder;
  RigImportOptions options;
  options.width = 640;
  options.height = 480;
  const auto errorWith = [&](const std::string& intri) {
    writeEasyMocap(folder.path(), truth, true);
    folder.write("intri.yml", intri);
    return testing::errorOf([&] { importEasyMocapRig(folder.path(), options); });
  };
  const std::string names = "%YAML:1.0\n---\nnames:\n   - \"cam01\"\n";
  std::string e = errorWith(names + "K_cam01: !!opencv-matrix\n   rows: 3\n   : 3\n");
  EXPECT_NE(e.find("intri.yml: cannot read as an OpenCV FileStorage file"), std::string::npos) << e;
  e = errorWith(names +
                "K_cam01: !!opencv-matrix\n   rows: 3\n   cols: 900000000\n   dt: d\n"
                "   data: [1]\n");
  EXPECT_NE(e.find("intri.yml: K_cam01: expected a matrix of at most 4096 numbers"),
            std::string::npos)
      << e;
  const std::string camera =
      "K_cam01: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\ndist_cam01: [0, 0, 0, 0, 0]\n";
  e = errorWith(names + camera + "W_cam01: 1e300\nH_cam01: 480\n");
  EXPECT_NE(e.find("intri.yml: W_cam01: expected a whole number of pixels"), std::string::npos)
      << e;
  e = errorWith("%YAML:1.0\n---\nnames:\n   - \"cam 1/../x\"\n");
  EXPECT_NE(e.find("intri.yml: names: 'cam 1/../x' is not a camera name"), std::string::npos) << e;
  e = errorWith(names + camera + "--x\n");
  EXPECT_NE(e.find("intri.yml:11: a line at column 0 starting with '-'"), std::string::npos) << e;
}

}  // namespace
}  // namespace lumistage
