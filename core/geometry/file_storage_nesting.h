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

// Everything checked of a FileStorage file's text before OpenCV reads it, each found by fuzzing
// OpenCV 4.6 (tests/fuzz): its nesting (above); no NUL byte (the XML parser dereferenced a null
// pointer on one; no FileStorage text holds one); YAML as one document with its top level at
// column 0 (the YAML parser looped forever on some text after a first document); and XML with a
// closed declaration and OpenCV's root element (the XML parser crashed on "<?xml version=").
// Throws Error "source:line: ...".
void checkFileStorageText(std::string_view text, const std::string& source);

}  // namespace lumistage
