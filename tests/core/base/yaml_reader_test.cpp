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

TEST(YamlReader, DeepNestingIsAnErrorNotACrash) {
  // yaml-cpp recurses per level of nesting, under a depth guard: 100,000 levels of flow or block
  // collections must end in an Error naming the file, not a stack overflow.
  const YamlReader in("deep.yaml");
  const int depth = 100000;
  for (const std::string& text : {std::string(depth, '[') + std::string(depth, ']'),
                                  [&] {
                                    std::string t;
                                    for (int i = 0; i < depth; ++i) t += "{a: ";
                                    return t + "1" + std::string(depth, '}');
                                  }(),
                                  [&] {
                                    std::string t;
                                    for (int i = 0; i < 5000; ++i) t += std::string(i, ' ') + "-\n";
                                    return t;
                                  }()}) {
    const std::string e = testing::errorOf([&] { in.parseDocument(text); });
    EXPECT_EQ(e.rfind("deep.yaml", 0), 0u) << e.substr(0, 300);
  }
}

TEST(YamlReader, TextFromTheFileIsQuotedAndCut) {
  const YamlReader in("test.yaml");
  // A 20 MB scalar with a terminal escape in it: 200 bytes of it come back, escaped.
  const YAML::Node root = in.parseDocument("a: \"\\e[2J" + std::string(20'000'000, 'x') + "\"\n");
  const std::string e = testing::errorOf([&] { in.number(root["a"], "a"); });
  EXPECT_LT(e.size(), 400u);
  EXPECT_NE(e.find("got '\\x1b[2Jxxx"), std::string::npos) << e;
  EXPECT_NE(e.find("... (20000004 bytes in all)"), std::string::npos) << e;
  EXPECT_EQ(e.find('\x1b'), std::string::npos);
  // A key with a line break in it cannot forge a line of the message.
  const YAML::Node keys = in.parseDocument("\"bad\\nkey\": 1\n");
  const std::string k = testing::errorOf([&] { in.checkKeys(keys, "", {"good"}); });
  EXPECT_EQ(k, "test.yaml:1: 'bad\\nkey': unknown key 'bad\\nkey'; expected one of: good");
  // Another kind of file read as YAML (/etc/passwd is one long text): its contents stay out.
  const YAML::Node passwd =
      in.parseDocument("root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin\n");
  const std::string p = testing::errorOf([&] { in.requireMap(passwd, ""); });
  EXPECT_EQ(p.find("root:x"), std::string::npos) << p;
  EXPECT_NE(p.find("not a YAML file of this kind"), std::string::npos) << p;
}

}  // namespace
}  // namespace lumistage
