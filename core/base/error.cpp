#include "core/base/error.h"

#include <fmt/format.h>

#include <cstdint>

namespace lumistage {

std::string locate(std::string_view file, int line, std::string_view key,
                   std::string_view message) {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) out += ":" + std::to_string(line);
    out += ": ";
  }
  if (!key.empty()) {
    out += key;
    out += ": ";
  }
  out += message;
  return out;
}

namespace {

// The length of the UTF-8 sequence of a printable character at `text[i]`, or 0 (a lone or cut
// continuation byte, an overlong or surrogate form, a C1 control character, U+2028/9 line breaks).
size_t printableUtf8(std::string_view text, size_t i) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  size_t length = 0;
  uint32_t code = 0;
  if (lead >= 0xc2 && lead <= 0xdf) {
    length = 2;
    code = lead & 0x1f;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    code = lead & 0x0f;
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    code = lead & 0x07;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xc0) != 0x80) return 0;
    code = code << 6 | (byte(i + k) & 0x3f);
  }
  const bool overlong = (length == 3 && code < 0x800) || (length == 4 && code < 0x10000);
  const bool control = code < 0xa0 || code == 0x2028 || code == 0x2029;  // C1, line breaks
  const bool invalid = (code >= 0xd800 && code <= 0xdfff) || code > 0x10ffff;
  return overlong || control || invalid ? 0 : length;
}

}  // namespace

std::string quotedInput(std::string_view text, size_t limit) {
  std::string out = "'";
  size_t i = 0;
  while (i < text.size() && i < limit) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\\' || c == '\'') {
      out += '\\';
      out += static_cast<char>(c);
      ++i;
    } else if (c == '\n') {
      out += "\\n";
      ++i;
    } else if (c == '\t') {
      out += "\\t";
      ++i;
    } else if (c == '\r') {
      out += "\\r";
      ++i;
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
      ++i;
    } else if (const size_t n = c >= 0x80 ? printableUtf8(text, i) : 0; n > 0 && i + n <= limit) {
      out.append(text.substr(i, n));
      i += n;
    } else if (n > 0) {
      break;  // a character cut by the limit
    } else {
      out += fmt::format("\\x{:02x}", c);
      ++i;
    }
  }
  out += '\'';
  if (i < text.size()) out += fmt::format("... ({} bytes in all)", text.size());
  return out;
}

std::string printableInput(std::string_view text, size_t limit) {
  bool plain = text.size() <= limit;
  for (size_t i = 0; plain && i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      ++i;
    } else if (const size_t n = c >= 0x80 ? printableUtf8(text, i) : 0; n > 0) {
      i += n;
    } else {
      plain = false;
    }
  }
  return plain ? std::string(text) : quotedInput(text, limit);
}

}  // namespace lumistage
