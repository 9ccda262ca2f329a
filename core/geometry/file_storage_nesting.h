#pragma once

#include <string>
#include <string_view>

namespace lumistage {

// OpenCV's FileStorage parsers (YAML, XML, JSON) descend by recursion, with no limit: a file
// nesting 100,000 levels overflows the stack (SIGSEGV). The text's nesting is measured before
// OpenCV reads it, every way a FileStorage format nests (indentation, "- " items, [ ] and { }
// outside quotes, XML elements), counting generously; a file deeper than kMaxFileStorageNesting
// is refused with Error "source:line: ...". Calibration files nest a few levels.
inline constexpr int kMaxFileStorageNesting = 64;
void checkFileStorageNesting(std::string_view text, const std::string& source);

}  // namespace lumistage
