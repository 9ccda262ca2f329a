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

}  // namespace lumistage
