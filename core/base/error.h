#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace lumistage {

// An error at an I/O or configuration boundary. Its message says what went wrong, where (file,
// line, key, camera) and what was expected, so that it can be shown to a user as it is. Hot paths
// never throw; they return values.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "file:line: key: message", leaving out the parts that are unknown (empty file, line <= 0,
// empty key). Lines count from 1, as editors show them.
std::string locate(std::string_view file, int line, std::string_view key, std::string_view message);

// Text from an input (a file, the network) for a message: in single quotes, at most `limit` bytes
// of it (then "... (N bytes in all)"), with control bytes, bytes that are not UTF-8 and the quote
// and backslash escaped ("\x1b", "\n", "\'"). A message so never prints megabytes of a file,
// moves a terminal's cursor or forges a log line.
std::string quotedInput(std::string_view text, size_t limit = 200);

// Free text from an input shown among other text (a node's last error in a report): as it is when
// it is at most `limit` bytes of printable UTF-8 (no control byte), otherwise its quotedInput()
// form. Plain text reads as it did; nothing else can move a cursor or forge a line.
std::string printableInput(std::string_view text, size_t limit = 200);

}  // namespace lumistage
