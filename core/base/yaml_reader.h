#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>
#include <string_view>

namespace lumistage {

// Reads configuration YAML strictly, so that every mistake in a hand-edited file becomes an Error
// of the form "file:line: key.path: expected ..., got ...". Keys are given as dotted paths
// ("cameras[3].intrinsics.fx") and reported as such.
class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  // Parses a whole document; a syntax error or an empty document is an Error with its line.
  YAML::Node parseDocument(std::string_view text) const;

  [[noreturn]] void fail(const YAML::Node& at, std::string_view key,
                         std::string_view message) const;

  // A map's entry that must exist: an Error naming the key and what was expected if it does not.
  YAML::Node required(const YAML::Node& map, std::string_view map_key, const char* key,
                      std::string_view expected) const;
  void requireMap(const YAML::Node& node, std::string_view key) const;
  // A sequence, of exactly `size` entries unless size < 0.
  void requireSequence(const YAML::Node& node, std::string_view key, int size = -1) const;
  // Rejects keys outside `allowed` and keys given twice: a misspelt or repeated key must not be
  // silently ignored.
  void checkKeys(const YAML::Node& map, std::string_view key,
                 std::initializer_list<std::string_view> allowed) const;

  double number(const YAML::Node& value, std::string_view key) const;  // finite only
  int integer(const YAML::Node& value, std::string_view key) const;
  std::string string(const YAML::Node& value, std::string_view key) const;
  bool boolean(const YAML::Node& value, std::string_view key) const;  // true or false

  static std::string child(std::string_view parent, std::string_view key);
  static std::string item(std::string_view parent, size_t index);

 private:
  std::string source_;
};

}  // namespace lumistage
