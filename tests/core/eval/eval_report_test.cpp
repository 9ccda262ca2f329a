// The evaluation report: sections of figures in order, a per-frame table, flat JSON.
#include "core/eval/eval_report.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lumistage {
namespace {

TEST(EvalReport, KeepsSectionsAndKeysInOrderAndWritesFlatJson) {
  EvalReport r;
  r.setText("session", "session", "out/walk \"1\"");
  r.set("mocap", "mpjpe_mm", 21.5);
  r.set("mocap", "frames", 3);
  r.set("refine", "hull_mm", std::nan(""));
  r.set("mocap", "mpjpe_mm", 20.25);  // a key set again keeps its place
  ASSERT_EQ(r.sections().size(), 3u);
  EXPECT_EQ(r.sections()[1].name, "mocap");
  ASSERT_EQ(r.sections()[1].entries.size(), 2u);
  EXPECT_EQ(r.find("mpjpe_mm")->number, 20.25);
  EXPECT_EQ(r.find("missing"), nullptr);
  r.setFrame(2, "mpjpe_mm", 19.5);
  r.setFrame(0, "mpjpe_mm", 22);
  r.setFrame(0, "pose_ms", 4.5);
  EXPECT_EQ(r.frameRows(), 2u);
  EXPECT_EQ(r.toJson(),
            "{\n"
            "  \"session\": \"out/walk \\\"1\\\"\",\n"
            "  \"mpjpe_mm\": 20.25,\n"
            "  \"frames\": 3,\n"
            "  \"hull_mm\": null,\n"
            "  \"per_frame\": [\n"
            "    {\"frame\": 0, \"mpjpe_mm\": 22, \"pose_ms\": 4.5},\n"
            "    {\"frame\": 2, \"mpjpe_mm\": 19.5, \"pose_ms\": null}\n"
            "  ]\n"
            "}\n");
  EXPECT_NE(r.toText().find("mocap\n  mpjpe_mm  20.25\n"), std::string::npos) << r.toText();
}

}  // namespace
}  // namespace lumistage
