#include "core/base/error.h"
#include "core/base/status.h"

#include <gtest/gtest.h>

#include <string>

namespace lumistage {
namespace {

TEST(QuotedInput, EscapesWhatATerminalOrALogWouldObey) {
  EXPECT_EQ(quotedInput("cam1"), "'cam1'");
  EXPECT_EQ(quotedInput(""), "''");
  // Escape sequences, line breaks (a forged log line), quotes and backslashes.
  EXPECT_EQ(quotedInput("a\x1b[2Jb"), "'a\\x1b[2Jb'");
  EXPECT_EQ(quotedInput("node\n[info] forged"), "'node\\n[info] forged'");
  EXPECT_EQ(quotedInput("it's a\\b"), "'it\\'s a\\\\b'");
  EXPECT_EQ(quotedInput(std::string("a\0b", 3)), "'a\\x00b'");
  EXPECT_EQ(quotedInput("\x7f"), "'\\x7f'");
  // UTF-8 text stays readable; broken UTF-8 and C1 controls (0x9b is a CSI on some terminals) do
  // not.
  EXPECT_EQ(quotedInput("K\xc3\xa4the"), "'K\xc3\xa4the'");
  EXPECT_EQ(quotedInput("\xc2\x9b"
                        "2J"),
            "'\\xc2\\x9b2J'");
  EXPECT_EQ(quotedInput("\xff\xc3"), "'\\xff\\xc3'");
}

TEST(QuotedInput, TruncatesLongTextAndSaysHowLongItWas) {
  const std::string scalar(2'000'000, 'x');
  const std::string q = quotedInput(scalar);
  EXPECT_EQ(q, "'" + std::string(200, 'x') + "'... (2000000 bytes in all)");
  EXPECT_EQ(quotedInput("abcdef", 3), "'abc'... (6 bytes in all)");
  // A character the limit would cut is left out whole.
  EXPECT_EQ(quotedInput("ab\xc3\xa4", 3), "'ab'... (4 bytes in all)");
}

TEST(Status, OkHoldsNoReasonAndAFailureAlwaysOne) {
  const Status ok;
  EXPECT_TRUE(ok.ok());
  EXPECT_EQ(ok.error(), "");
  const Status failed = Status::failure("cam01/000003.png: is truncated");
  EXPECT_FALSE(failed.ok());
  EXPECT_EQ(failed.error(), "cam01/000003.png: is truncated");
  // A failure without words is still a failure, and says so.
  const Status silent = Status::failure("");
  EXPECT_FALSE(silent.ok());
  EXPECT_NE(silent.error(), "");
}

TEST(PrintableInput, KeepsPlainTextAndQuotesTheRest) {
  EXPECT_EQ(printableInput("lost: reconnecting"), "lost: reconnecting");
  EXPECT_EQ(printableInput("K\xc3\xa4the's disk"), "K\xc3\xa4the's disk");
  EXPECT_EQ(printableInput("ok\n[2024-01-01] [info] forged"), "'ok\\n[2024-01-01] [info] forged'");
  EXPECT_EQ(printableInput("a\x1b[2Jb"), "'a\\x1b[2Jb'");
  EXPECT_EQ(printableInput("\xc2\x9b"
                           "2J"),
            "'\\xc2\\x9b2J'");
  EXPECT_EQ(printableInput(std::string(300, 'x')),
            "'" + std::string(200, 'x') + "'... (300 bytes in all)");
}

}  // namespace
}  // namespace lumistage
