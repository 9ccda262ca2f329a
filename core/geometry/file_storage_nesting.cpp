#include "core/geometry/file_storage_nesting.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

[[noreturn]] void refuse(const std::string& source, int line) {
  throw Error(fmt::format("{}:{}: nested deeper than {} levels: refused before reading it", source,
                          line, kMaxFileStorageNesting));
}

// YAML and JSON: a line's indentation levels (a stack of indents, a "- " item one more each),
// plus the [ ] and { } open at any point of it. An opening bracket always counts; a closing one
// only outside a quoted string (strings end at their line's end), so that quoting can only make
// the measure larger.
void checkIndentedNesting(std::string_view text, const std::string& source) {
  std::vector<size_t> indents;
  int brackets = 0, line = 1;
  for (size_t start = 0; start < text.size(); ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view row = text.substr(start, end - start);
    start = end + 1;
    size_t p = row.find_first_not_of(" \t\r");
    if (p == std::string_view::npos || row[p] == '#') continue;
    while (!indents.empty() && indents.back() >= p) indents.pop_back();
    indents.push_back(p);
    while (p < row.size() && row[p] == '-' && (p + 1 == row.size() || row[p + 1] == ' ')) {
      p = row.find_first_not_of(' ', p + 1);
      if (p == std::string_view::npos) p = row.size();
      indents.push_back(p);
    }
    if (static_cast<int>(indents.size()) + brackets > kMaxFileStorageNesting) refuse(source, line);
    char quote = 0;
    for (size_t i = p; i < row.size(); ++i) {
      const char c = row[i];
      if (quote != 0) {
        if (c == '\\' && quote == '"')
          ++i;
        else if (c == quote)
          quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '#' && (i == 0 || row[i - 1] == ' ' || row[i - 1] == '\t')) {
        break;
      }
      if (c == '[' || c == '{') {
        if (static_cast<int>(indents.size()) + ++brackets > kMaxFileStorageNesting)
          refuse(source, line);
      } else if ((c == ']' || c == '}') && quote == 0 && brackets > 0) {
        --brackets;
      }
    }
  }
}

// XML: elements open, less those closed ("</"); comments, declarations and self-closing
// elements ("<a/>") do not nest. Quoted attribute values are skipped.
void checkXmlNesting(std::string_view text, const std::string& source) {
  int depth = 0, line = 1;
  const auto skipTo = [&](size_t& i, std::string_view end) {
    const size_t found = text.find(end, i);
    const size_t stop = found == std::string_view::npos ? text.size() : found + end.size();
    for (; i < stop; ++i)
      if (text[i] == '\n') ++line;
    --i;  // the loop's ++i steps past
  };
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
    } else if (text[i] == '<') {
      const std::string_view rest = text.substr(i);
      if (rest.starts_with("<!--")) {
        skipTo(i, "-->");
      } else if (rest.starts_with("<?") || rest.starts_with("<!")) {
        skipTo(i, ">");
      } else if (rest.starts_with("</")) {
        depth = depth > 0 ? depth - 1 : 0;
        skipTo(i, ">");
      } else {
        // The tag up to its '>', quoted values skipped: "/>" closes it at once.
        char quote = 0, last = 0;
        size_t j = i + 1;
        for (; j < text.size(); ++j) {
          const char c = text[j];
          if (c == '\n') ++line;
          if (quote != 0) {
            if (c == quote) quote = 0;
          } else if (c == '"' || c == '\'') {
            quote = c;
          } else if (c == '>') {
            break;
          } else if (c != ' ' && c != '\t' && c != '\r' && c != '\n') {
            last = c;
          }
        }
        if (last != '/' && ++depth > kMaxFileStorageNesting) refuse(source, line);
        i = j;
        if (i >= text.size()) return;
      }
    }
  }
}

// OpenCV 4.6's YAML parser loops forever where a document after its first starts with '-' but not
// "---" ("--- a: 0\n--x", "a: 0\n---\n -"): past a document it skips three bytes, taking them for
// "---" or "...", and then waits for a "---" that never comes. So one document only, whose top
// level starts at column 0 (then no line can end it before the end of the file): "---" alone on
// its line and before the content, "..." only after it all, no line at column 0 starting with
// '-' (OpenCV refuses a sequence at column 0 under a key anyway; a calibration's top level is a
// mapping).
void checkYamlDocument(std::string_view text, const std::string& source) {
  const auto refuse = [&](int line, std::string_view what) {
    throw Error(fmt::format("{}:{}: {}: only one YAML document, its keys at column 0, is read",
                            source, line, what));
  };
  bool content = false, ended = false;
  int line = 1;
  for (size_t start = 0; start < text.size(); ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view row = text.substr(start, end - start);
    start = end + 1;
    const size_t first = row.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || row[first] == '#') continue;
    if (ended) refuse(line, "text after the document's end '...'");
    if (row.starts_with("---")) {
      const size_t rest = row.find_first_not_of(" \t\r", 3);
      if (content) refuse(line, "a second document '---'");
      if (rest != std::string_view::npos && rest == 3) refuse(line, "a line starting with '---'");
      if (rest != std::string_view::npos && row[rest] != '#')
        refuse(line, "content on the document's start line '---'");
    } else if (row.starts_with("...")) {
      ended = true;
    } else if (row.starts_with('%') && !content) {
      // A directive (%YAML:1.0).
    } else if (row.starts_with('-')) {
      refuse(line, "a line at column 0 starting with '-'");
    } else if (!content && first != 0) {
      refuse(line, "the document's first key not at column 0");
    } else {
      content = true;
    }
  }
}

}  // namespace

void checkFileStorageText(std::string_view text, const std::string& source) {
  if (const size_t nul = text.find('\0'); nul != std::string_view::npos) {
    const auto line = 1 + std::count(text.begin(), text.begin() + std::ptrdiff_t(nul), '\n');
    throw Error(
        fmt::format("{}:{}: a NUL byte: not a text file (OpenCV YAML, XML or JSON)", source, line));
  }
  checkFileStorageNesting(text, source);
  // YAML as OpenCV tells it: "%YAML" first, after a UTF-8 byte order mark.
  const std::string_view body = text.starts_with("\xef\xbb\xbf") ? text.substr(3) : text;
  if (body.starts_with("%YAML")) checkYamlDocument(text, source);
  // XML as OpenCV tells it ("<" first, after blanks): its parser dereferenced a null pointer on a
  // declaration cut short ("<?xml version="). The declaration must close, and the root element be
  // OpenCV's.
  const size_t first = body.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && body[first] == '<') {
    const std::string_view xml = body.substr(first);
    if (xml.starts_with("<?") && xml.find("?>") == std::string_view::npos)
      throw Error(fmt::format("{}:1: an XML declaration that does not end ('?>')", source));
    if (xml.find("<opencv_storage") == std::string_view::npos)
      throw Error(fmt::format("{}: XML without OpenCV's root element <opencv_storage>", source));
  }
}

void checkFileStorageNesting(std::string_view text, const std::string& source) {
  // Both measures whatever the file's name or first bytes: OpenCV picks the format by either.
  checkXmlNesting(text, source);
  checkIndentedNesting(text, source);
}

}  // namespace lumistage
