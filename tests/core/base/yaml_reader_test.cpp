#include "core/base/yaml_reader.h"

#include <gtest/gtest.h>

#include "core/base/error.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(YamlReader, NumbersMustBeWholeAndFinite) {
  const YamlReader in("test.yaml");
  const YAML::Node root = in.parseDocument("a: 1.5\nb: 12abc\nc: .inf\nd: [1]\ne: 3\n");
  EXPECT_DOUBLE_EQ(in.number(root["a"], "a"), 1.5);
  EXPECT_EQ(in.integer(root["e"], "e"), 3);
  EXPECT_EQ(testing::errorOf([&] { in.number(root["b"], "b"); }),
            "test.yaml:2: b: expected a finite number, got '12abc'");
  EXPECT_EQ(testing::errorOf([&] { in.number(root["c"], "c"); }),
            "test.yaml:3: c: expected a finite number, got '.inf'");
  EXPECT_EQ(testing::errorOf([&] { in.number(root["d"], "d"); }),
            "test.yaml:4: d: expected a finite number, got a list");
  EXPECT_EQ(testing::errorOf([&] { in.integer(root["a"], "a"); }),
            "test.yaml:1: a: expected a whole number, got '1.5'");
}

TEST(YamlReader, MissingAndUnknownKeys) {
  const YamlReader in("test.yaml");
  const YAML::Node root = in.parseDocument("outer:\n  alpha: 1\n  betta: 2\n");
  EXPECT_EQ(testing::errorOf([&] { in.required(root["outer"], "outer", "gamma", "a number"); }),
            "test.yaml:2: outer.gamma: missing key 'gamma': expected a number");
  EXPECT_EQ(testing::errorOf([&] {
              in.checkKeys(root["outer"], "outer", {"alpha", "beta"});
            }),
            "test.yaml:3: outer.betta: unknown key 'betta'; expected one of: alpha, beta");
  // A key given twice (YAML would keep the first and ignore the edit below it).
  const YAML::Node twice = in.parseDocument("outer:\n  alpha: 1\n  beta: 2\n  alpha: 3\n");
  EXPECT_EQ(testing::errorOf([&] {
              in.checkKeys(twice["outer"], "outer", {"alpha", "beta"});
            }),
            "test.yaml:4: outer.alpha: given twice (first at line 2)");
}

TEST(YamlReader, SyntaxErrorsCarryTheirLine) {
  const YamlReader in("test.yaml");
  const std::string e = testing::errorOf([&] { in.parseDocument("a: 1\nb: [1, 2\nc: 3\n"); });
  EXPECT_EQ(e.rfind("test.yaml:", 0), 0u) << e;
  EXPECT_NE(e.find("YAML syntax error"), std::string::npos) << e;
}

}  // namespace
}  // namespace lumistage
