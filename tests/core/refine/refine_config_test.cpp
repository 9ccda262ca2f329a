// The studio config's `refine:` section: read over the defaults, mistakes named.
#include "core/refine/refine_config.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/body/human_model.h"
#include "core/sim/studio_config.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(RefineConfig, ReadFromTheStudioConfigOverTheDefaults) {
  const auto folder = testing::testFolder("refine_config");
  const std::string head =
      "format: lumistage-studio\nversion: 1\nrig: " +
      (std::filesystem::path(LUMISTAGE_TEST_RESOURCE_DIR) / "rigs" / "reference.yaml").string() +
      "\n";
  // The refine section read from a file holding `refine`.
  const auto refineFrom = [&](const char* name, const std::string& refine) {
    std::ofstream(folder / name) << head << "refine:\n" << refine;
    return loadStudioConfig(folder / name).refine;
  };
  std::ofstream(folder / "a.yaml")
      << head
      << "refine:\n  t_max_m: 0.05\n  t_inward_m: 0.05\n  offset_count: 11\n"
         "  colour_weight: 0.5\n";
  const StudioConfig config = loadStudioConfig(folder / "a.yaml");
  EXPECT_DOUBLE_EQ(config.refine.t_max_m, 0.05);
  EXPECT_EQ(config.refine.offset_count, 11);
  EXPECT_DOUBLE_EQ(config.refine.colour_weight, 0.5);
  EXPECT_DOUBLE_EQ(config.refine.outside_weight, RefineConfig{}.outside_weight);
  EXPECT_DOUBLE_EQ(config.refine.offsetAt(0), -0.05);
  EXPECT_DOUBLE_EQ(config.refine.offsetAt(5), 0.0);
  EXPECT_DOUBLE_EQ(config.refine.offsetAt(10), 0.05);
  // By default the range reaches further out than in, 5 mm a step, the posed surface among them.
  const RefineConfig defaults;
  EXPECT_NEAR(defaults.offsetAt(1) - defaults.offsetAt(0), 0.005, 1e-12);
  EXPECT_NEAR(defaults.offsetAt(defaults.offset_count - 1), defaults.t_max_m, 1e-12);
  EXPECT_GT(defaults.t_max_m, defaults.t_inward_m);
  EXPECT_NEAR(defaults.offsetAt(defaults.zeroOffsetIndex()), 0.0, 1e-12);
  EXPECT_NEAR(defaults.levelOffset(defaults.zeroLevel()), 0.0, 1e-12);
  // An asymmetric range: 2 cm in, 6 cm out, 9 offsets.
  const RefineConfig g =
      refineFrom("g.yaml", "  t_inward_m: 0.02\n  t_max_m: 0.06\n  offset_count: 9\n");
  EXPECT_DOUBLE_EQ(g.offsetAt(0), -0.02);
  EXPECT_DOUBLE_EQ(g.offsetAt(8), 0.06);
  EXPECT_EQ(g.zeroOffsetIndex(), 2);
  EXPECT_NEAR(g.offsetAt(2), 0.0, 1e-12);
  EXPECT_EQ(g.zeroLevel(), 16);

  std::ofstream(folder / "b.yaml") << head << "refine:\n  t_max: 0.05\n";
  EXPECT_NE(testing::errorOf([&] { loadStudioConfig(folder / "b.yaml"); }).find("refine"),
            std::string::npos);
  // A file holding `refine`, and the error loading it gives.
  const auto errorFor = [&](const char* name, const std::string& refine) {
    return testing::errorOf([&] { refineFrom(name, refine); });
  };
  EXPECT_NE(errorFor("h.yaml", "  t_inward_m: -0.01\n")
                .find("h.yaml:5: refine.t_inward_m: expected metres in [0, 0.5]"),
            std::string::npos);
  EXPECT_NE(errorFor("c.yaml", "  colour_bits: 9\n")
                .find("c.yaml:5: refine.colour_bits: expected 1 to 8 bits"),
            std::string::npos);
  // The colour window: 1 or 3 points, at most 5 cm to either side.
  const RefineConfig d = refineFrom("d.yaml", "  window_points: 1\n  window_m: 0.02\n");
  EXPECT_EQ(d.window_points, 1);
  EXPECT_DOUBLE_EQ(d.window_m, 0.02);
  EXPECT_EQ(RefineConfig{}.window_points, 3);
  EXPECT_NE(errorFor("e.yaml", "  window_points: 2\n")
                .find("e.yaml:5: refine.window_points: expected 1 or 3 points"),
            std::string::npos);
  EXPECT_NE(errorFor("f.yaml", "  window_m: 0.1\n")
                .find("f.yaml:5: refine.window_m: expected metres in [0, 0.05]"),
            std::string::npos);
  // The contour term: its weight, the facing that counts as edge-on and the probe's reach.
  const RefineConfig i =
      refineFrom("i.yaml", "  contour_weight: 0\n  contour_cos: 0.2\n  contour_probe_m: 0.03\n");
  EXPECT_EQ(i.contour_weight, 0.0);
  EXPECT_DOUBLE_EQ(i.contour_cos, 0.2);
  EXPECT_DOUBLE_EQ(i.contour_probe_m, 0.03);
  EXPECT_GT(RefineConfig{}.contour_weight, 0.0);
  EXPECT_NE(errorFor("j.yaml", "  contour_cos: 1.5\n")
                .find("j.yaml:5: refine.contour_cos: expected a cosine in [0, 1]"),
            std::string::npos);
  EXPECT_NE(errorFor("k.yaml", "  contour_weight: -1\n")
                .find("k.yaml:5: refine.contour_weight: expected a weight >= 0"),
            std::string::npos);
  // Which pixels' colours a point takes: a share of the key's bound, above 0.
  EXPECT_DOUBLE_EQ(refineFrom("l.yaml", "  colour_purity: 1\n").colour_purity, 1.0);
  EXPECT_LT(RefineConfig{}.colour_purity, 1.0);
  EXPECT_NE(errorFor("m.yaml", "  colour_purity: 0\n")
                .find("m.yaml:5: refine.colour_purity: expected a share in [0.01, 1]"),
            std::string::npos);
  // The spill suppression, on by default; true or false only. The refined surface's tolerance.
  const RefineConfig no_despill =
      refineFrom("n.yaml", "  despill: false\n  refined_depth_tolerance_m: 0.02\n");
  EXPECT_FALSE(no_despill.despill);
  EXPECT_DOUBLE_EQ(no_despill.refined_depth_tolerance_m, 0.02);
  EXPECT_TRUE(RefineConfig{}.despill);
  EXPECT_LT(RefineConfig{}.refined_depth_tolerance_m, RefineConfig{}.depth_tolerance_m);
  EXPECT_NE(errorFor("o.yaml", "  despill: 1\n")
                .find("o.yaml:5: refine.despill: expected true or false, got '1'"),
            std::string::npos);
  EXPECT_NE(errorFor("p.yaml", "  refined_depth_tolerance_m: -0.01\n")
                .find("p.yaml:5: refine.refined_depth_tolerance_m: expected metres in [0, 1]"),
            std::string::npos);
  // The outward term off the contours: its own weight; the nodes mark the contours for it alone.
  const RefineConfig l =
      refineFrom("l.yaml", "  contour_weight: 0\n  off_contour_outward_weight: 0.3\n");
  EXPECT_DOUBLE_EQ(l.off_contour_outward_weight, 0.3);
  EXPECT_TRUE(l.marksContours());
  RefineConfig same = l;
  same.off_contour_outward_weight = same.outward_weight;
  EXPECT_FALSE(same.marksContours());
  EXPECT_LT(RefineConfig{}.off_contour_outward_weight, RefineConfig{}.outward_weight);
  EXPECT_NE(errorFor("m.yaml", "  off_contour_outward_weight: -0.5\n")
                .find("m.yaml:5: refine.off_contour_outward_weight: expected a weight >= 0"),
            std::string::npos);
  // The smoothness's reference density: the weight as given at it, in proportion elsewhere; 0
  // turns the scaling off.
  const RefineConfig r =
      refineFrom("r.yaml", "  smooth_weight: 3\n  smooth_reference_vertices: 1000\n");
  EXPECT_EQ(r.smooth_reference_vertices, 1000);
  EXPECT_DOUBLE_EQ(r.smoothWeightFor(1000), 3.0);
  EXPECT_DOUBLE_EQ(r.smoothWeightFor(4000), 12.0);
  EXPECT_DOUBLE_EQ(refineFrom("s.yaml", "  smooth_reference_vertices: 0\n").smoothWeightFor(4000),
                   RefineConfig{}.smooth_weight);
  EXPECT_NE(errorFor("t.yaml", "  smooth_reference_vertices: -1\n")
                .find("t.yaml:5: refine.smooth_reference_vertices: expected a vertex count >= 0"),
            std::string::npos);
}

// The default smoothness is set for the standard generic human, and the fine one takes it in
// proportion to its vertices: about twice as strong.
TEST(RefineConfig, TheSmoothnessIsSetForTheStandardBodyAndFollowsTheFineOnesDensity) {
  const RefineConfig config;
  const int standard = loadGenericHuman(BodyDetail::kStandard).rest.vertexCount();
  const int fine = loadGenericHuman(BodyDetail::kFine).rest.vertexCount();
  EXPECT_EQ(config.smooth_reference_vertices, standard);
  EXPECT_DOUBLE_EQ(config.smoothWeightFor(standard), config.smooth_weight);
  EXPECT_GT(config.smoothWeightFor(fine), 2 * config.smooth_weight);
}

}  // namespace
}  // namespace lumistage
