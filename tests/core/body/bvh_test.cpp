#include "core/body/bvh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>

#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

fs::path testFolder() {
  return testing::testFolder("bvh");
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// CMU-style names, Y up, centimetres, the actor facing +Z (so its right is -X). RHipJoint has no
// counterpart in our skeleton: its rotation must fold into right_hip. 36 channels.
constexpr const char* kCmuStyle = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT RHipJoint
  {
    OFFSET -5 0 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    JOINT RightUpLeg
    {
      OFFSET -5 0 0
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT RightLeg
      {
        OFFSET 0 -45 0
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT RightFoot
        {
          OFFSET 0 -45 0
          CHANNELS 3 Zrotation Yrotation Xrotation
          End Site
          {
            OFFSET 0 -5 10
          }
        }
      }
    }
  }
  JOINT LowerBack
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    JOINT Spine
    {
      OFFSET 0 10 0
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT RightShoulder
      {
        OFFSET -5 15 0
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT RightArm
        {
          OFFSET -15 0 0
          CHANNELS 3 Zrotation Yrotation Xrotation
          JOINT RightForeArm
          {
            OFFSET -28 0 0
            CHANNELS 3 Zrotation Yrotation Xrotation
            JOINT RightHand
            {
              OFFSET -25 0 0
              CHANNELS 3 Zrotation Yrotation Xrotation
              End Site
              {
                OFFSET -9 0 0
              }
            }
          }
        }
      }
    }
  }
}
MOTION
Frames: 4
Frame Time: 0.008333333
0 95 0 0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0
10 100 -20 0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 90 0  0 0 0
0 95 0 0 90 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0
0 95 0 0 0 0  0 0 30  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0
)";

TEST(Bvh, NamesMapToOurs) {
  EXPECT_EQ(humanJointNameFor("Hips"), "pelvis");
  EXPECT_EQ(humanJointNameFor("mixamorig:RightForeArm"), "right_elbow");
  EXPECT_EQ(humanJointNameFor("LeftUpLeg"), "left_hip");
  EXPECT_EQ(humanJointNameFor("LeftToeBase"), "left_foot");
  EXPECT_EQ(humanJointNameFor("RightCollar"), "right_clavicle");
  EXPECT_EQ(humanJointNameFor("Spine"), "spine1");
  EXPECT_EQ(humanJointNameFor("Spine", JointNaming::kCmu), "spine2");
  EXPECT_EQ(humanJointNameFor("LeftShoulder"), "left_clavicle");
  EXPECT_EQ(humanJointNameFor("LeftShoulder", JointNaming::kBiovision), "left_shoulder");
  EXPECT_EQ(humanJointNameFor("RightElbow", JointNaming::kBiovision), "right_elbow");
  EXPECT_EQ(humanJointNameFor("RightWrist", JointNaming::kBiovision), "right_wrist");
  EXPECT_EQ(humanJointNameFor("Chest", JointNaming::kBiovision), "spine3");
  EXPECT_EQ(humanJointNameFor("left_knee"), "left_knee");
  EXPECT_EQ(humanJointNameFor("RHipJoint"), std::nullopt);
}

TEST(Bvh, SaveThenLoadReproducesJointPositions) {
  const fs::path folder = testFolder();
  BodyShape shape;
  shape.height_m = 1.62;
  const Skeleton s = makeHumanSkeleton(shape);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  MotionClip clip;
  clip.name = "random";
  clip.fps = 50;
  for (int f = 0; f < 6; ++f) {
    Pose pose = Pose::rest(s.jointCount());
    pose.root_translation_m = Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    pose.angles_rad[0] = Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, 6 * unit(rng) - 3);
    for (int j = 1; j < s.jointCount(); ++j) {
      const JointLimits& l = s.joint(j).limits;
      for (int a = 0; a < 3; ++a) {
        pose.angles_rad[j][a] = l.lower_rad[a] + unit(rng) * (l.upper_rad[a] - l.lower_rad[a]);
      }
    }
    clip.frames.push_back(pose);
  }
  saveBvh(clip, s, folder / "random.bvh");
  const MotionClip loaded = loadBvh(folder / "random.bvh", s);
  EXPECT_EQ(loaded.name, "random");
  EXPECT_NEAR(loaded.fps, 50, 1e-6);
  ASSERT_EQ(loaded.frames.size(), clip.frames.size());
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    std::vector<Eigen::Vector3d> expected, actual;
    s.jointPositions(clip.frames[f], expected);
    s.jointPositions(loaded.frames[f], actual);
    for (int j = 0; j < s.jointCount(); ++j) {
      EXPECT_LT((expected[j] - actual[j]).norm(), 1e-6) << "frame " << f << " " << s.joint(j).name;
    }
  }
  fs::remove_all(folder);
}

TEST(Bvh, CmuStyleFileRetargetsOntoOurSkeleton) {
  const fs::path folder = testFolder();
  writeText(folder / "walk.bvh", kCmuStyle);
  const Skeleton s = makeHumanSkeleton();
  const MotionClip clip = loadBvh(folder / "walk.bvh", s);
  EXPECT_EQ(clip.name, "walk");
  EXPECT_NEAR(clip.fps, 120, 1e-3);
  ASSERT_EQ(clip.frames.size(), 4u);
  const auto& rest = s.restPositions();
  // Root heights: 95 cm in the file (hips above the toe end site) and ours above our lowest joint.
  double lowest = rest[0].z();
  for (const auto& p : rest) lowest = std::min(lowest, p.z());
  const double scale = (rest[kPelvis].z() - lowest) / 95.0;

  // Frame 1: the rest pose where the file stands: our rest pose.
  EXPECT_LT(clip.frames[0].root_translation_m.norm(), 1e-12);
  for (const auto& a : clip.frames[0].angles_rad) EXPECT_LT(a.norm(), 1e-12);

  // Frame 2: moved 10 cm to its left (our -x), 5 cm up, 20 cm back (our -y); right forearm turned
  // 90 degrees about the vertical: it points forward (+y), as our elbow's z angle does.
  const Pose& bent = clip.frames[1];
  EXPECT_LT((bent.root_translation_m - scale * Eigen::Vector3d(-10, -20, 5)).norm(), 1e-9);
  EXPECT_LT((bent.angles_rad[kRightElbow] - Eigen::Vector3d(0, 0, kPi / 2)).norm(), 1e-9);
  std::vector<Eigen::Vector3d> p;
  s.jointPositions(bent, p);
  const double forearm = (rest[kRightWrist] - rest[kRightElbow]).norm();
  EXPECT_LT((p[kRightElbow] - (rest[kRightElbow] + bent.root_translation_m)).norm(), 1e-9);
  EXPECT_LT((p[kRightWrist] - (p[kRightElbow] + Eigen::Vector3d(0, forearm, 0))).norm(), 1e-9);

  // Frame 3: the whole body turned 90 degrees to its left about the vertical.
  EXPECT_LT((clip.frames[2].angles_rad[0] - Eigen::Vector3d(0, 0, kPi / 2)).norm(), 1e-9);

  // Frame 4: the unmapped RHipJoint turned 30 degrees about the file's X (our -x): folded into
  // right_hip, whose parent (pelvis) did not turn.
  EXPECT_LT((clip.frames[3].angles_rad[kRightHip] - Eigen::Vector3d(-kPi / 6, 0, 0)).norm(), 1e-9);
  for (int j : {kSpine3, kNeck, kLeftHip, kRightKnee}) {
    EXPECT_LT(clip.frames[3].angles_rad[j].norm(), 1e-12) << s.joint(j).name;
  }
  fs::remove_all(folder);
}

// Real files' frame counts disagree with their frame lines (an exporter that counted before the
// take ended, a copy cut short): every whole frame line is read, whatever 'Frames:' says.
// A file whose rest pose is not ours (its right thigh splayed outward, its right upper arm
// hanging down): at zero rotations our bones lie where the file's do, not where ours rest.
TEST(Bvh, ARestPoseThatIsNotOursKeepsTheBonesWhereTheFileHasThem) {
  std::string text = kCmuStyle;
  const auto replaceFirst = [&](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replaceFirst("OFFSET 0 -45 0", "OFFSET -15 -42 0");  // RightLeg: the knee out to the right
  replaceFirst("OFFSET -28 0 0", "OFFSET 0 -28 0");    // RightForeArm: the elbow below
  const fs::path folder = testFolder();
  writeText(folder / "rest.bvh", text);
  const Skeleton s = makeHumanSkeleton();
  const MotionClip clip = loadBvh(folder / "rest.bvh", s);
  std::vector<Eigen::Vector3d> p;
  s.jointPositions(clip.frames[0], p);
  // The file's x is our -x, its y our z.
  const Eigen::Vector3d thigh = (p[kRightKnee] - p[kRightHip]).normalized();
  EXPECT_LT((thigh - Eigen::Vector3d(15, 0, -42).normalized()).norm(), 1e-9);
  const Eigen::Vector3d upper_arm = (p[kRightElbow] - p[kRightShoulder]).normalized();
  EXPECT_LT((upper_arm - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);
  // The rest of the body is ours at rest.
  const auto& rest = s.restPositions();
  for (int j : {kLeftKnee, kLeftAnkle, kSpine3, kHead})
    EXPECT_LT((p[j] - p[kPelvis] - (rest[j] - rest[kPelvis])).norm(), 1e-9) << s.joint(j).name;
  fs::remove_all(folder);
}

// Real files made by others (../shared/realdata/motions, where present): the CMU actor stands with
// his legs apart, not crossed (its rest pose splays the legs); the Biovision boxer's elbows bend
// (its Shoulder is the upper arm, its Collar the clavicle).
TEST(Bvh, RealCmuAndBiovisionFilesComeInAsTheActorMoved) {
  const fs::path motions = testing::realData() / "motions";
  if (!fs::exists(motions / "cmu-01_03.bvh") || !fs::exists(motions / "boxing-biovision.bvh"))
    GTEST_SKIP() << "no " << motions.string();
  const Skeleton s = makeHumanSkeleton();
  const MotionClip cmu = loadBvh(motions / "cmu-01_03.bvh", s);
  std::vector<Eigen::Vector3d> p;
  for (size_t f = 0; f <= 120; f += 60) {
    s.jointPositions(cmu.frames[f], p);
    const Eigen::Vector3d across = (p[kLeftHip] - p[kRightHip]).normalized();
    EXPECT_GT((p[kLeftKnee] - p[kRightKnee]).dot(across), 0.1) << "frame " << f;
    EXPECT_GT((p[kLeftAnkle] - p[kRightAnkle]).dot(across), 0.1) << "frame " << f;
  }
  const MotionClip boxing = loadBvh(motions / "boxing-biovision.bvh", s);
  double most_bent = 0;
  for (const Pose& pose : boxing.frames)
    most_bent = std::max(most_bent, pose.angles_rad[kRightElbow].norm());
  EXPECT_GT(most_bent, 1.0);
}

TEST(Bvh, FramesAreTheFramesLinesWhateverTheHeaderAnnounces) {
  const fs::path folder = testFolder();
  const Skeleton s = makeHumanSkeleton();
  const std::string good = kCmuStyle;
  const auto framesOf = [&](const std::string& text) {
    writeText(folder / "real.bvh", text);
    return loadBvh(folder / "real.bvh", s).frames.size();
  };
  std::string more = good;
  more.replace(more.find("Frames: 4"), 9, "Frames: 2");
  EXPECT_EQ(framesOf(more), 4u);
  std::string huge = good;
  huge.replace(huge.find("Frames: 4"), 9, "Frames: 1000000000000000");
  EXPECT_EQ(framesOf(huge), 4u);
  EXPECT_EQ(framesOf(good.substr(0, good.rfind("0 95 0 0 0 0"))), 3u);
  // CRLF line ends and tabs between the values.
  std::string windows;
  for (char c : good) {
    if (c == '\n')
      windows += "\r\n";
    else
      windows += c == ' ' ? '\t' : c;
  }
  EXPECT_EQ(framesOf(windows), 4u);
  fs::remove_all(folder);
}

TEST(Bvh, MalformedFilesNameFileLineAndWhatWasExpected) {
  const fs::path folder = testFolder();
  const Skeleton s = makeHumanSkeleton();
  const std::string good = kCmuStyle;
  auto load = [&](const std::string& text) {
    writeText(folder / "bad.bvh", text);
    return testing::errorOf([&] { loadBvh(folder / "bad.bvh", s); });
  };
  auto contains = [](const std::string& m, const std::string& part) {
    return m.find(part) != std::string::npos;
  };
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };

  // Truncated in the hierarchy.
  std::string m = load(good.substr(0, good.find("JOINT RightArm")));
  EXPECT_TRUE(contains(m, "bad.bvh:")) << m;
  EXPECT_TRUE(contains(m, "truncated")) << m;
  // Truncated in the motion before its first frame.
  m = load(good.substr(0, good.find("Frame Time:")) + "Frame Time: 0.01\n");
  EXPECT_TRUE(contains(m, "truncated: expected 4 frames after 'Frames:', found none")) << m;
  // A frame line with a value missing (line 69 is frame 2).
  m = load(replaced("0 90 0  0 0 0\n", "0 90 0  0 0\n"));
  EXPECT_TRUE(contains(m, "bad.bvh:69:")) << m;
  EXPECT_TRUE(contains(m, "35 values, expected 36")) << m;
  // A value that is no number.
  m = load(replaced("0 90 0  0 0 0\n", "0 abc 0  0 0 0\n"));
  EXPECT_TRUE(contains(m, "bad.bvh:69:")) << m;
  EXPECT_TRUE(contains(m, "expected a number")) << m;
  EXPECT_TRUE(contains(m, "'abc'")) << m;
  // An unknown channel.
  m = load(replaced("OFFSET -28 0 0\n            CHANNELS 3 Zrotation",
                    "OFFSET -28 0 0\n            CHANNELS 3 Wrotation"));
  EXPECT_TRUE(contains(m, "unknown channel 'Wrotation'")) << m;
  EXPECT_TRUE(contains(m, "RightForeArm")) << m;
  // A missing opening brace.
  m = load(replaced("JOINT Spine\n    {\n", "JOINT Spine\n"));
  EXPECT_TRUE(contains(m, "expected '{'")) << m;
  EXPECT_TRUE(contains(m, "found 'OFFSET'")) << m;
  // A missing closing brace swallows MOTION into the hierarchy.
  m = load(replaced("}\nMOTION", "MOTION"));
  EXPECT_TRUE(contains(m, "expected '}' closing joint 'Hips'")) << m;
  // Not a BVH file, and no file at all.
  m = load("hello\n");
  EXPECT_TRUE(contains(m, "bad.bvh:1: expected 'HIERARCHY', found 'hello'")) << m;
  m = testing::errorOf([&] { loadBvh(folder / "missing.bvh", s); });
  EXPECT_TRUE(contains(m, "missing.bvh")) << m;
  fs::remove_all(folder);
}

TEST(Bvh, DeeplyNestedJointsAreReadWithoutRecursion) {
  // 100,000 joints, each the child of the one before: the parser once recursed per level and
  // ended with a stack overflow (SIGSEGV) on such a file.
  const fs::path folder = testFolder();
  constexpr int kDepth = 100000;
  std::string text =
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition "
      "Zposition\n";
  for (int j = 0; j < kDepth; ++j)
    text += "JOINT j" + std::to_string(j) + "\n{\nOFFSET 0 -1 0\nCHANNELS 0\n";
  text += "End Site\n{\nOFFSET 0 -1 0\n}\n";
  for (int j = 0; j <= kDepth; ++j) text += "}\n";
  text += "MOTION\nFrames: 1\nFrame Time: 0.01\n0 0 0\n";
  writeText(folder / "deep.bvh", text);
  const MotionClip clip = loadBvh(folder / "deep.bvh", makeHumanSkeleton());
  EXPECT_EQ(clip.frames.size(), 1u);
  // Cut short inside the nesting: an error naming the innermost open joint, not a crash.
  writeText(folder / "deep.bvh", text.substr(0, text.find("End Site")));
  const std::string m =
      testing::errorOf([&] { loadBvh(folder / "deep.bvh", makeHumanSkeleton()); });
  EXPECT_NE(m.find("expected '}' closing joint 'j99999'"), std::string::npos) << m;
}

TEST(Bvh, ValuesTooLargeForAStageAreRefusedWithTheirLine) {
  const fs::path folder = testFolder();
  const Skeleton s = makeHumanSkeleton();
  auto load = [&](const std::string& from, const std::string& to) {
    std::string text = kCmuStyle;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    writeText(folder / "bad.bvh", text.replace(at, from.size(), to));
    return testing::errorOf([&] { loadBvh(folder / "bad.bvh", s); });
  };
  // A root position of 1e308 is a number, but scaled to metres it is no place on a stage (it wrote
  // -nan into a session's truth).
  std::string m = load("10 100 -20 0 0 0", "1e308 100 -20 0 0 0");
  EXPECT_NE(m.find("bad.bvh:69: frame 2: the root is"), std::string::npos) << m;
  // OFFSETs whose sum overflows.
  m = load("OFFSET -5 0 0", "OFFSET -1.7e308 0 0");
  EXPECT_NE(m.find("bad.bvh:"), std::string::npos) << m;
  EXPECT_NE(m.find("at rest"), std::string::npos) << m;
  m = load("OFFSET 0 -45 0", "OFFSET 0 nan 0");
  EXPECT_NE(m.find("expected a number for OFFSET, found 'nan'"), std::string::npos) << m;
  // Text echoed from the file is quoted, its control bytes escaped: no terminal escape gets out.
  m = load("10 100 -20", "10 \x1b[2J -20");
  EXPECT_NE(m.find("'\\x1b[2J'"), std::string::npos) << m;
  EXPECT_EQ(m.find('\x1b'), std::string::npos) << m;
}

}  // namespace
}  // namespace lumistage
