#include "core/body/gltf_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// An array or object open around the scan's position.
struct Level {
  bool object = false;
  bool expecting_key = true;  // objects: the next string is a key
  std::string key;            // objects: the key of the value being read
  int64_t index = 0;          // arrays: the index of the value being read
};

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// A JSON string's contents from its opening quote at text[i]; i ends past its closing quote. Simple
// escapes and \u escapes of ASCII characters are decoded (enough to compare keys), others kept as
// '?'. Returns false when the text ends inside it.
bool readString(std::string_view text, size_t& i, std::string& out) {
  out.clear();
  for (++i; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      ++i;
      return true;
    }
    if (c != '\\') {
      out += c;
      continue;
    }
    if (++i >= text.size()) return false;
    const char e = text[i];
    if (e == 'u') {
      unsigned code = 0;
      for (int k = 0; k < 4 && i + 1 < text.size(); ++k) {
        const int h = hexDigit(text[i + 1]);
        if (h < 0) break;
        code = code * 16 + unsigned(h);
        ++i;
      }
      out += code < 0x80 ? static_cast<char>(code) : '?';
    } else {
      static constexpr std::string_view kFrom = "ntrbf", kTo = "\n\t\r\b\f";
      const size_t k = kFrom.find(e);
      out += k == std::string_view::npos ? e : kTo[k];  // \" \\ \/ as themselves
    }
  }
  return false;
}

}  // namespace

void checkGltfJsonNesting(std::string_view text, std::string_view file,
                          const GltfNestingLimits& limits) {
  auto fail = [&](const std::string& message) {
    throw Error(locate(file, 0, "", message + ": refused before reading it"));
  };
  // The scan keeps the levels open around it (never recursing itself) and collects the node
  // hierarchy: glTF 2 lists nodes in an array and children by index, glTF 1 in an object and by
  // name. Either way a node is named by a string here.
  std::vector<Level> levels;
  std::unordered_map<std::string, int> node_index;
  std::vector<std::string> node_names;
  std::vector<std::pair<int, std::string>> edges;  // parent, child's name
  auto nodeOf = [&](const std::string& name) {
    const auto [it, added] = node_index.emplace(name, int(node_names.size()));
    if (added) node_names.push_back(name);
    return it->second;
  };
  // Whether the value being read is an entry of a node's "children", and whose.
  auto childOf = [&]() -> int {
    if (levels.size() != 4 || !levels[0].object || levels[0].key != "nodes" || !levels[2].object ||
        levels[2].key != "children" || levels[3].object)
      return -1;
    return nodeOf(levels[1].object ? levels[1].key : std::to_string(levels[1].index));
  };
  std::string word;
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '{' || c == '[') {
      if (levels.size() == 2 && levels[0].object && levels[0].key == "nodes") {
        nodeOf(levels[1].object ? levels[1].key : std::to_string(levels[1].index));
      }
      if (int(levels.size()) >= limits.json_depth) {
        fail(fmt::format("its JSON nests arrays and objects deeper than {} levels",
                         limits.json_depth));
      }
      levels.push_back({c == '{', true, {}, 0});
      ++i;
    } else if (c == '}' || c == ']') {
      if (levels.empty()) return;  // malformed: Assimp says so
      levels.pop_back();
      ++i;
    } else if (c == ',') {
      if (!levels.empty()) {
        ++levels.back().index;
        levels.back().expecting_key = true;
      }
      ++i;
    } else if (c == ':') {
      if (!levels.empty()) levels.back().expecting_key = false;
      ++i;
    } else if (c == '"') {
      if (!readString(text, i, word)) return;
      if (!levels.empty() && levels.back().object && levels.back().expecting_key) {
        levels.back().key = word;
      } else if (const int parent = childOf(); parent >= 0) {
        edges.emplace_back(parent, word);
      }
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else {
      // A number or a literal.
      size_t end = i;
      while (end < text.size() && std::strchr(",:]}[{\" \t\r\n", text[end]) == nullptr) ++end;
      if (const int parent = childOf(); parent >= 0) {
        edges.emplace_back(parent, std::string(text.substr(i, end - i)));
      }
      i = end;
    }
  }

  // The hierarchy: every node the child of at most one, every one reached from a root, and no
  // path from a root longer than the limit. A child that names no node is Assimp's to refuse.
  const int count = int(node_names.size());
  std::vector<std::vector<int>> children(count);
  std::vector<int> parent(count, -1);
  for (const auto& [from, name] : edges) {
    const auto it = node_index.find(name);
    if (it == node_index.end()) continue;
    const int to = it->second;
    if (parent[to] >= 0) {
      fail(
          fmt::format("node {} is a child of node {} and of node {}: a glTF node hierarchy must be "
                      "a set of trees",
                      quotedInput(name, 64), quotedInput(node_names[parent[to]], 64),
                      quotedInput(node_names[from], 64)));
    }
    parent[to] = from;
    children[from].push_back(to);
  }
  std::vector<std::pair<int, int>> stack;  // node, its depth (roots 1)
  int reached = 0;
  for (int n = 0; n < count; ++n) {
    if (parent[n] < 0) stack.emplace_back(n, 1);
  }
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    ++reached;
    if (depth > limits.node_depth) {
      fail(fmt::format("its nodes nest deeper than {} levels (node {})", limits.node_depth,
                       quotedInput(node_names[node], 64)));
    }
    for (int child : children[node]) stack.emplace_back(child, depth + 1);
  }
  if (reached < count) {
    fail(
        fmt::format("{} of its nodes are their own ancestors: a glTF node hierarchy must be a set "
                    "of trees",
                    count - reached));
  }
}

void checkGltfNesting(const fs::path& path, const GltfNestingLimits& limits) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;  // the importer says why
  std::array<char, 20> header{};
  in.read(header.data(), header.size());
  const size_t got = size_t(in.gcount());
  auto little32 = [&](size_t at) {
    uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(header[at + k]);
    return v;
  };
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  std::string json;
  if (got >= 20 && std::memcmp(header.data(), "glTF", 4) == 0) {
    // Binary glTF: version 2 has chunks (length, type "JSON", the JSON); version 1 its content's
    // length, format 0 and the JSON.
    const uint32_t version = little32(4);
    const uint32_t length = little32(12);
    const bool json_chunk = version == 2 && std::memcmp(header.data() + 16, "JSON", 4) == 0;
    const bool json_content = version == 1 && little32(16) == 0;
    if (!json_chunk && !json_content) return;
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    if (ec || length > size) return;  // cut short: Assimp refuses it
    json.resize(length);
    in.seekg(20);
    in.read(json.data(), std::streamsize(length));
    json.resize(size_t(in.gcount()));
  } else if (ext == ".gltf") {
    in.seekg(0);
    json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } else {
    return;  // not glTF
  }
  checkGltfJsonNesting(json, path.string(), limits);
}

}  // namespace lumistage
