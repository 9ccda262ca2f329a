#include "core/base/yaml_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <utility>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

int lineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return quotedInput(node.Scalar());
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    default:
      return "nothing";
  }
}

// A key of the file as a part of a dotted key path: as it is when it is a plain word, else quoted
// (a key of megabytes or of terminal escapes is the file's text too).
std::string keyInPath(const std::string& name) {
  const bool plain =
      !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
      });
  return plain ? name : quotedInput(name);
}

}  // namespace

YAML::Node YamlReader::parseDocument(std::string_view text) const {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::ParserException& e) {
    throw Error(
        locate(source_, e.mark.is_null() ? 0 : e.mark.line + 1, "",
               "YAML syntax error: " + e.msg + " (is the file truncated or mis-indented?)"));
  }
  if (!root || root.IsNull()) throw Error(locate(source_, 0, "", "the file is empty"));
  return root;
}

void YamlReader::fail(const YAML::Node& at, std::string_view key, std::string_view message) const {
  throw Error(locate(source_, lineOf(at), key, message));
}

YAML::Node YamlReader::required(const YAML::Node& map, std::string_view map_key, const char* key,
                                std::string_view expected) const {
  YAML::Node value = map[key];
  if (!value.IsDefined()) {
    fail(map, map_key.empty() ? std::string(key) : child(map_key, key),
         "missing key '" + std::string(key) + "': expected " + std::string(expected));
  }
  return value;
}

void YamlReader::requireMap(const YAML::Node& node, std::string_view key) const {
  if (node.IsMap()) return;
  // A whole document that is one text is another kind of file (`rig: /etc/passwd`): its contents
  // are not for the message.
  if (key.empty() && node.IsScalar()) {
    fail(node, key,
         "expected a map of keys, got text (" + std::to_string(node.Scalar().size()) +
             " bytes): not a YAML file of this kind");
  }
  fail(node, key, "expected a map of keys, got " + describe(node));
}

void YamlReader::requireSequence(const YAML::Node& node, std::string_view key, int size) const {
  if (!node.IsSequence()) {
    fail(node, key,
         size < 0 ? "expected a list, got " + describe(node)
                  : "expected a list of " + std::to_string(size) + ", got " + describe(node));
  }
  if (size >= 0 && node.size() != static_cast<size_t>(size)) {
    fail(node, key,
         "expected a list of " + std::to_string(size) + ", got " + std::to_string(node.size()) +
             " entries");
  }
}

void YamlReader::checkKeys(const YAML::Node& map, std::string_view key,
                           std::initializer_list<std::string_view> allowed) const {
  std::vector<std::pair<std::string, int>> seen;  // the keys so far, and their lines
  for (const auto& entry : map) {
    const std::string name = entry.first.Scalar();
    // YAML keeps the first of two equal keys: the second, a hand edit, would be ignored.
    for (const auto& [other, line] : seen) {
      if (other == name)
        fail(entry.first, child(key, keyInPath(name)),
             "given twice (first at line " + std::to_string(line) + ")");
    }
    seen.emplace_back(name, entry.first.Mark().line + 1);
    bool known = false;
    for (std::string_view a : allowed) known = known || name == a;
    if (!known) {
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      fail(entry.first, child(key, keyInPath(name)),
           "unknown key " + quotedInput(name) + "; expected one of: " + list);
    }
  }
}

bool YamlReader::boolean(const YAML::Node& value, std::string_view key) const {
  const std::string text = value.IsScalar() ? value.Scalar() : std::string();
  if (text != "true" && text != "false")
    fail(value, key, "expected true or false, got " + describe(value));
  return text == "true";
}

double YamlReader::number(const YAML::Node& value, std::string_view key) const {
  double out = 0;
  if (!value.IsScalar() || !YAML::convert<double>::decode(value, out) || !std::isfinite(out)) {
    fail(value, key, "expected a finite number, got " + describe(value));
  }
  return out;
}

int YamlReader::integer(const YAML::Node& value, std::string_view key) const {
  int out = 0;
  if (!value.IsScalar() || !YAML::convert<int>::decode(value, out)) {
    fail(value, key, "expected a whole number, got " + describe(value));
  }
  return out;
}

std::string YamlReader::string(const YAML::Node& value, std::string_view key) const {
  if (!value.IsScalar()) fail(value, key, "expected a text value, got " + describe(value));
  return value.Scalar();
}

std::string YamlReader::child(std::string_view parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  return std::string(parent) + "." + std::string(key);
}

std::string YamlReader::item(std::string_view parent, size_t index) {
  return std::string(parent) + "[" + std::to_string(index) + "]";
}

}  // namespace lumistage
